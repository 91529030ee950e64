"""Working on stored actions: ``hfpbd executor actions list|show|rename|delete``.

The same operations answer the ``executor/control/actions`` queryable, so the
command line (which edits the store directly, no service needed) and the TUI
(which asks the running service) behave alike.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
from collections.abc import Sequence
from datetime import datetime
from typing import Any

from services.executor.grounding import describe_kind
from services.executor.skills import give_name
from services.executor.store import (
    DEFAULT_NAMESPACE,
    ActionStore,
    StoreError,
    default_data_dir,
    namespace_dir,
)


def apply_action_op(store: ActionStore, request: dict[str, Any]) -> dict[str, Any]:
    """Run one ``{"op": ...}`` request on ``store``; raises ``StoreError`` with a reason on bad input."""
    op = request.get("op")
    if op == "list":
        return {"ok": True, "actions": store.summaries(), "current": store.current}
    number: Any = request.get("number")  # any JSON value; the store refuses what is not an action number
    if isinstance(number, str) and number.isdigit():
        number = int(number)
    if op == "show":
        return {"ok": True, "number": number, "action": store.get(number)}
    if op == "rename":
        name = request.get("name")
        if not isinstance(name, str):
            raise StoreError("rename needs a name")
        give_name(store, number, name)
        return {"ok": True, "number": number, "name": name.strip()}
    if op == "delete":
        store.delete(number)
        return {"ok": True, "number": number, "current": store.current}
    raise StoreError(f"unknown actions operation {op!r}; use list, show, rename or delete")


def _step_line(index: int, step: dict[str, Any]) -> str:
    words = step.get("utterance") or step.get("text") or step["procedure"].replace("_", " ")
    landmark = step.get("landmark")
    about = f"  [{describe_kind(landmark)}]" if landmark else ""
    return f"  {index}. {words}{about}"


def _print_list(reply: dict[str, Any]) -> None:
    if not reply["actions"]:
        print("No actions yet.")
        return
    for item in reply["actions"]:
        mark = "*" if item["current"] else " "
        name = item["name"] or "(unnamed)"
        created = datetime.fromtimestamp(item["created"]).strftime("%Y-%m-%d %H:%M") if item.get("created") else ""
        print(f"{mark} {item['number']:>3}  {name:<24} {item['steps']:>3} steps  {created}")


def _print_action(reply: dict[str, Any]) -> None:
    action = reply["action"]
    print(f"Action {reply['number']}: {action.get('name') or '(unnamed)'}, {len(action['steps'])} steps")
    for i, step in enumerate(action["steps"], start=1):
        print(_step_line(i, step))


def main(argv: Sequence[str]) -> int:
    # --data-dir and --json are accepted before or after the operation word
    common = argparse.ArgumentParser(add_help=False)
    common.add_argument(
        "--data-dir",
        default=argparse.SUPPRESS,
        help=f"where actions are stored, in DIR/<namespace>/ (default: {default_data_dir()})",
    )
    common.add_argument(
        "--namespace",
        "-n",
        default=argparse.SUPPRESS,
        help="whose actions: the robot's namespace (default: $HFPBD_NAMESPACE or default)",
    )
    common.add_argument("--json", action="store_true", default=argparse.SUPPRESS, help="print the reply as JSON")
    parser = argparse.ArgumentParser(
        prog="hfpbd executor actions", parents=[common], description="list, show, rename and delete programmed actions"
    )
    sub = parser.add_subparsers(dest="op", required=True)
    sub.add_parser("list", parents=[common], help="one line per action")
    show = sub.add_parser("show", parents=[common], help="the steps of one action")
    show.add_argument("number", type=int)
    rename = sub.add_parser("rename", parents=[common], help="give an action a name")
    rename.add_argument("number", type=int)
    rename.add_argument("name")
    delete = sub.add_parser("delete", parents=[common], help="remove an action (later ones move down by one)")
    delete.add_argument("number", type=int)
    args = parser.parse_args(list(argv))
    data_dir, as_json = getattr(args, "data_dir", None), getattr(args, "json", False)
    namespace = getattr(args, "namespace", None) or os.environ.get("HFPBD_NAMESPACE", DEFAULT_NAMESPACE)
    request = {k: v for k, v in vars(args).items() if k not in ("data_dir", "json", "namespace")}
    try:
        reply = apply_action_op(ActionStore(namespace_dir(data_dir, namespace)), request)
    except StoreError as exc:
        print(f"hfpbd executor actions: {exc}", file=sys.stderr)
        return 1
    if as_json:
        print(json.dumps(reply, indent=1))
    elif args.op == "list":
        _print_list(reply)
    elif args.op == "show":
        _print_action(reply)
    elif args.op == "rename":
        print(f"Renamed action {reply['number']} to {reply['name']!r}.")
    else:
        print(f"Deleted action {reply['number']}.")
    return 0
