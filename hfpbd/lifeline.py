"""``python -m hfpbd.lifeline PARENT_PID -m MODULE ARGS…``: run MODULE, ending when PARENT_PID ends.

Why: the services ``hfpbd up`` starts must not outlive it, however it ends —
SIGKILL leaves it no chance to clean up. On Linux a process can ask the
kernel for a signal when its parent dies (``prctl(PR_SET_PDEATHSIG)``);
asking from here, after the exec, avoids running Python between fork and
exec in a parent full of threads. The kernel ties the request to the
parent's *thread* that started the child, so start children from a thread
that lives as long as they should (the main thread). Kept free of heavy
imports: it runs before every service.
"""

from __future__ import annotations

import ctypes
import os
import runpy
import signal
import sys

_PR_SET_PDEATHSIG = 1


def end_with_parent(parent: int, sig: int = signal.SIGTERM) -> None:
    """Receive ``sig`` when ``parent`` dies; a parent already gone (we were re-parented) ends us now."""
    if sys.platform.startswith("linux"):
        ctypes.CDLL(None, use_errno=True).prctl(_PR_SET_PDEATHSIG, sig)
    if os.getppid() != parent:
        os.kill(os.getpid(), sig)


def command(module: str, *args: str) -> list[str]:
    """The argv that runs ``python -m module args…`` tied to this process."""
    return [sys.executable, "-m", "hfpbd.lifeline", str(os.getpid()), "-m", module, *args]


def main() -> None:
    if len(sys.argv) < 4 or sys.argv[2] != "-m":
        sys.exit("usage: python -m hfpbd.lifeline PARENT_PID -m MODULE [ARGS...]")
    end_with_parent(int(sys.argv[1]))
    module = sys.argv[3]
    sys.argv = [module, *sys.argv[4:]]
    runpy.run_module(module, run_name="__main__", alter_sys=True)


if __name__ == "__main__":
    main()
