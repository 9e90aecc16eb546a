"""Text commands that drive a running simulator's fault injection (`--control` reads them from stdin).

    silence 13 14     the servos (or 200, the CM-740) stop answering
    revive 13         they answer again
    corrupt 5         the next 5 status packets go out with a bad checksum
    power on|off      switch the servo power as the CM-740 would
    positions         present positions of all joints
    stats             packet counters

Each command gets one JSON line back: {"ok": true, ...} or {"ok": false, "error": "..."}.
"""

from __future__ import annotations

from typing import Any

from services.motion.simbus.bus import SimBus


def _ids(args: list[str]) -> list[int]:
    if not args:
        raise ValueError("give one or more device ids, e.g. 'silence 13'")
    ids = [int(a) for a in args]
    if not all(0 <= i <= 253 for i in ids):
        raise ValueError("device ids are 0..253")
    return ids


def apply_command(bus: SimBus, line: str) -> dict[str, Any]:
    """Run one command line against `bus`; never raises on bad input."""
    words = line.split()
    if not words:
        return {"ok": False, "error": "empty command"}
    cmd, args = words[0].lower(), words[1:]
    try:
        if cmd == "silence":
            bus.silence(*_ids(args))
        elif cmd == "revive":
            bus.revive(*_ids(args))
        elif cmd == "corrupt":
            if len(args) != 1 or int(args[0]) < 0:
                raise ValueError("usage: corrupt <count>")
            bus.corrupt_replies(int(args[0]))
        elif cmd == "stray":
            if len(args) != 1:
                raise ValueError("usage: stray <id>")
            bus.stray_reply(_ids(args)[0])
        elif cmd == "power":
            if args not in (["on"], ["off"]):
                raise ValueError("usage: power on|off")
            bus.set_power(args[0] == "on")
        elif cmd == "positions":
            return {"ok": True, "positions": bus.present_positions()}
        elif cmd == "stats":
            stats = bus.stats
            return {
                "ok": True,
                "packets": stats.packets,
                "sync_writes": stats.sync_writes,
                "bulk_reads": stats.bulk_reads,
                "bad_checksums": stats.bad_checksums,
                "corrupted": stats.corrupted,
            }
        else:
            raise ValueError(f"unknown command {cmd!r}: silence, revive, corrupt, stray, power, positions, stats")
    except ValueError as exc:
        return {"ok": False, "error": str(exc)}
    return {"ok": True}
