"""`python -m services.motion.simbus`: serve a simulated OP2 bus and print its device path.

The first line on stdout is the pty path (e.g. /dev/pts/7); point any Dynamixel tool at it at
1,000,000 bps. Runs until SIGTERM, Ctrl-C, or (with --parent-pid) until that process is gone.
With --control, fault-injection commands are read from stdin, one per line (see
services/motion/simbus/control.py: silence, revive, corrupt, stray, power, positions, stats), each answered
with one JSON line on stdout.
"""

from __future__ import annotations

import json
import os
import sys
import threading
from typing import Annotated

import typer

from services.motion.simbus.bus import SimBus
from services.motion.simbus.control import apply_command
from services.runtime.signals import stop_on_signals

app = typer.Typer(add_completion=False, help=__doc__, rich_markup_mode=None)  # help text as written


@app.command()
def main(
    powered: Annotated[
        bool, typer.Option(help="Start with the servo bus powered (the robot boots unpowered)")
    ] = False,
    wire_time: Annotated[bool, typer.Option(help="Model 1 Mbps wire time and reply delays")] = True,
    parent_pid: Annotated[int, typer.Option(help="Exit when this process is gone (0: never)")] = 0,
    control: Annotated[bool, typer.Option(help="Read fault-injection commands from stdin")] = False,
) -> None:
    """Serve the simulated bus until stopped."""
    stop = stop_on_signals()
    bus = SimBus(powered=powered, wire_time=wire_time).start()
    try:
        sys.stdout.write(bus.path + "\n")
        sys.stdout.flush()
        if control:
            threading.Thread(target=_serve_commands, args=(bus, stop), daemon=True).start()
        while not stop.wait(0.5):
            if parent_pid and os.getppid() != parent_pid:
                break
    finally:
        bus.stop()


def _serve_commands(bus: SimBus, stop: threading.Event) -> None:
    for line in sys.stdin:
        if line.strip():
            sys.stdout.write(json.dumps(apply_command(bus, line)) + "\n")
            sys.stdout.flush()
    stop.set()  # stdin closed: the controlling process is gone


if __name__ == "__main__":
    app()
