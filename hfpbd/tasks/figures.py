"""The task benchmark's outputs: a table (text, Markdown, CSV), the comparison with the paper, a Fig. 6-style chart.

Works on plain row dicts (``RunReport.as_dict()``), so the outputs can be
regenerated from a saved ``tasks.json`` without running the robot again.
"""

from __future__ import annotations

import csv
import statistics
from pathlib import Path
from typing import Any

from hfpbd.tasks.scripts import STYLES
from shared import stats

TASK4_CONVERSATIONAL_WORDS = 20  # the conversational style's word budget for Task 4 (the paper's minimal: 27)
COLOURS = {"full": "#4c72b0", "minimal": "#dd8452", "conversational": "#55a868"}
COLUMNS = ("task", "style", "utterances", "words", "success", "programming_s", "replay", "median_latency_ms")


def table_rows(runs: list[dict[str, Any]]) -> list[dict[str, Any]]:
    rows = []
    for run in runs:
        latencies = [s["motion_latency_s"] for s in run["steps"] if s.get("motion_latency_s") is not None]
        rows.append(
            {
                "task": f"{run['task']} {run['title']}",
                "style": run["style"],
                "utterances": run["utterances"],
                "words": run["words"],
                "success": "yes" if run["success"] else "no",
                "programming_s": f"{run['programming_s']:.1f}",
                "replay": "yes" if run["replay"] else "no",
                "median_latency_ms": f"{1000 * statistics.median(latencies):.0f}" if latencies else "-",
            }
        )
    return rows


def text_table(rows: list[dict[str, Any]]) -> str:
    widths = {c: max(len(c), *(len(str(r[c])) for r in rows)) if rows else len(c) for c in COLUMNS}
    lines = ["  ".join(c.ljust(widths[c]) for c in COLUMNS)]
    lines += ["  ".join(str(r[c]).ljust(widths[c]) for c in COLUMNS) for r in rows]
    return "\n".join(lines)


def markdown_table(rows: list[dict[str, Any]]) -> str:
    return stats.markdown_table(COLUMNS, [[r[c] for c in COLUMNS] for r in rows])


def write_csv(rows: list[dict[str, Any]], path: Path) -> None:
    with open(path, "w", newline="") as handle:
        writer = csv.DictWriter(handle, fieldnames=COLUMNS)
        writer.writeheader()
        writer.writerows(rows)


def _pairs(runs: list[dict[str, Any]]) -> dict[str, dict[str, dict[str, Any]]]:
    by_task: dict[str, dict[str, dict[str, Any]]] = {}
    for run in runs:
        by_task.setdefault(run["task"], {})[run["style"]] = run
    return by_task


def comparison(runs: list[dict[str, Any]], paper: dict[str, Any]) -> list[str]:
    """Sentences setting our figures next to the paper's (words, time saved, motion latency)."""
    lines = []
    below_half = set(paper.get("minimal_words_below_half", []))
    saved_paper = paper.get("time_saved_s", {})
    for task, styles in _pairs(runs).items():
        if not {"full", "minimal"} <= set(styles):
            continue
        full, minimal = styles["full"], styles["minimal"]
        ratio = minimal["words"] / full["words"]
        if task in below_half:
            claim = f"paper: under half ({'holds' if ratio < 0.5 else 'does NOT hold'} here)"
        elif task == "task4":
            p = paper.get("task4_words", {})
            claim = f"paper: {p.get('full')} -> {p.get('minimal')} words ({p.get('minimal', 0) / max(p.get('full', 1), 1):.0%})"
        else:
            claim = ""
        saved = full["programming_s"] - minimal["programming_s"]
        paper_saved = f"; paper saved ~{saved_paper[task]} s" if task in saved_paper else ""
        lines.append(
            f"{task}: words {full['words']} -> {minimal['words']} ({ratio:.0%}); {claim}; "
            f"programming time {full['programming_s']:.1f} s -> {minimal['programming_s']:.1f} s "
            f"(saved {saved:.1f} s{paper_saved})"
        )
    lines += _conversational(runs, paper)
    latencies = [s["motion_latency_s"] for r in runs for s in r["steps"] if s.get("motion_latency_s") is not None]
    target = paper.get("motion_latency_target_s", 0.2)
    if latencies:
        ordered = sorted(latencies)
        p95 = ordered[min(len(ordered) - 1, int(round(0.95 * (len(ordered) - 1))))]
        within = sum(v <= target for v in latencies)
        lines.append(
            f"utterance -> start of motion: median {1000 * statistics.median(latencies):.0f} ms, "
            f"95th percentile {1000 * p95:.0f} ms, max {1000 * ordered[-1]:.0f} ms over {len(latencies)} "
            f"moving steps; {within}/{len(latencies)} within the {1000 * target:.0f} ms target"
        )
    return lines


def _conversational(runs: list[dict[str, Any]], paper: dict[str, Any]) -> list[str]:
    """The conversational style against the minimal one, and Task 4 against its word budget."""
    lines = []
    for task, styles in _pairs(runs).items():
        talk = styles.get("conversational")
        if talk is None:
            continue
        line = f"{task}: conversational {talk['words']} words in {talk['utterances']} utterances"
        if "minimal" in styles:
            line += f" (minimal: {styles['minimal']['words']} in {styles['minimal']['utterances']})"
        if task == "task4":
            within = talk["words"] <= TASK4_CONVERSATIONAL_WORDS
            paper_minimal = paper.get("task4_words", {}).get("minimal")
            line += (
                f"; target <= {TASK4_CONVERSATIONAL_WORDS} words ({'met' if within else 'NOT met'}; "
                f"paper's minimal: {paper_minimal})"
            )
        done = "programmed" if talk.get("programmed", talk["success"]) else "NOT programmed"
        line += f"; {done}, success {'yes' if talk['success'] else 'no'}, replay {'yes' if talk['replay'] else 'no'}"
        lines.append(line)
    return lines


def chart(runs: list[dict[str, Any]], path: Path) -> None:
    """Two panels like the paper's Fig. 6(b, c): programming time and words per task, one bar per style run."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    pairs = _pairs(runs)
    tasks = sorted(pairs)
    styles = [style for style in STYLES if any(style in pairs[t] for t in tasks)]
    fig, axes = plt.subplots(1, 2, figsize=(10, 3.4))
    width = 0.8 / max(1, len(styles))
    for ax, field, label in ((axes[0], "programming_s", "Time (s)"), (axes[1], "words", "Number of words")):
        for n, style in enumerate(styles):
            offset, colour = (n - (len(styles) - 1) / 2) * width, COLOURS[style]
            values = [pairs[t].get(style, {}).get(field, 0) for t in tasks]
            failed = [not (pairs[t].get(style, {}).get("success")) for t in tasks]
            bars = ax.bar(
                [i + offset for i in range(len(tasks))], values, width, label=f"{style} language", color=colour
            )
            for bar, bad in zip(bars, failed):
                if bad:
                    bar.set_hatch("//")
        ax.set_xticks(range(len(tasks)), [t.replace("task", "Task ") for t in tasks])
        ax.set_ylabel(label)
        ax.grid(axis="y", alpha=0.3)
    axes[0].set_title("(b) time to program")
    axes[1].set_title("(c) words used")
    axes[1].legend(frameon=False, fontsize=8)
    fig.text(0.5, 0.005, "hatched: task not achieved", ha="center", fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
