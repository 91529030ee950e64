"""Session flags, the one config helper, and the hfpbd command."""

from __future__ import annotations

import argparse
import json
import re
import subprocess
import sys

import pytest

from shared.config import add_session_arguments, options_from_args, zenoh_config


def _parse(*argv: str) -> argparse.Namespace:
    parser = argparse.ArgumentParser()
    add_session_arguments(parser)
    return parser.parse_args(argv)


def test_flags_reach_the_zenoh_config() -> None:
    options = options_from_args(
        _parse(
            "--mode",
            "client",
            "-e",
            "tcp/10.0.0.2:7447",
            "-e",
            "tcp/10.0.0.3:7447",
            "--listen",
            "tcp/0.0.0.0:7448",
            "--no-multicast-scouting",
            "-n",
            "robot1",
            "--cfg",
            "transport/shared_memory/enabled:false",
            "--insecure",
        )
    )
    assert options.namespace == "robot1"
    config = zenoh_config(options)
    assert json.loads(config.get_json("mode")) == "client"
    assert json.loads(config.get_json("connect/endpoints")) == ["tcp/10.0.0.2:7447", "tcp/10.0.0.3:7447"]
    assert json.loads(config.get_json("listen/endpoints")) == ["tcp/0.0.0.0:7448"]
    assert json.loads(config.get_json("scouting/multicast/enabled")) is False
    assert json.loads(config.get_json("transport/shared_memory/enabled")) is False


def test_options_survive_a_round_trip_through_argv() -> None:
    options = options_from_args(_parse("-e", "tcp/h:1", "--no-multicast-scouting", "-n", "x"))
    assert options_from_args(_parse(*options.to_argv())) == options


def test_environment_supplies_defaults(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("HFPBD_CONNECT", "tcp/robot:7447, tcp/backup:7447")
    options = options_from_args(_parse())
    assert options.connect == ("tcp/robot:7447", "tcp/backup:7447")


@pytest.mark.parametrize(
    "argv, reason",
    [
        (("--cfg", "novalue"), "KEY:VALUE"),
        (("--namespace", "a/b"), "one key chunk"),
        (("--namespace", "*"), "one key chunk"),
    ],
)
def test_bad_flags_are_refused_with_reason(argv: tuple[str, ...], reason: str) -> None:
    with pytest.raises(ValueError, match=reason):
        options_from_args(_parse(*argv))


def _hfpbd(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "hfpbd.cli", *args], capture_output=True, text=True, timeout=60)


def test_version_prints_and_succeeds() -> None:
    result = _hfpbd("version")
    assert result.returncode == 0 and result.stdout.startswith("hfpbd ")


def test_unknown_command_is_refused_with_usage() -> None:
    result = _hfpbd("fly")
    assert result.returncode == 2
    assert "unknown command 'fly'" in result.stderr and "commands:" in result.stderr


def test_help_lists_every_service() -> None:
    out = _hfpbd("--help").stdout
    for command in ("sim", "perception", "nlu", "executor", "tui", "up", "bench", "version"):
        assert f"  {command}" in out


def test_bad_session_flag_exits_nonzero_with_one_line() -> None:
    result = subprocess.run(
        [sys.executable, "-m", "tests.echo_peer", "--namespace", "a/b"], capture_output=True, text=True, timeout=60
    )
    assert result.returncode == 2
    assert "one key chunk" in result.stderr and "Traceback" not in result.stderr


def test_a_listener_in_a_config_file_is_refused_in_one_line(tmp_path) -> None:
    file = tmp_path / "zenoh.json5"
    file.write_text('{listen: {endpoints: ["tcp/0.0.0.0:7447"]}}')
    result = subprocess.run(
        [sys.executable, "-m", "tests.echo_peer", "--config", str(file)],
        capture_output=True,
        text=True,
        timeout=60,
        check=False,
    )
    assert result.returncode == 2
    assert "--secure DIR" in result.stderr and "Traceback" not in result.stderr


def test_the_executor_benchmarks_planning_figures_print() -> None:
    """``hfpbd bench executor --skip-physics``: the reach-map table and the IK comparison, from a real process."""
    result = subprocess.run(
        [sys.executable, "-m", "hfpbd.cli", "bench", "executor", "--skip-physics", "--repeats", "1"],
        capture_output=True,
        text=True,
        timeout=300,
        check=False,
    )
    assert result.returncode == 0, result.stderr[-2000:]
    assert "Traceback" not in result.stderr
    rows = [line for line in result.stdout.splitlines() if re.match(r"\| \d+ \| \d+ \| \d+ \|", line)]
    assert [int(row.split("|")[1]) for row in rows] == [1, 2, 5, 10, 15]
    assert re.search(r"IK per pose: seeded table [\d.]+ ms .* same answer on \d+% of 100 poses", result.stdout)
