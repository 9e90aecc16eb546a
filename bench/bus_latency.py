"""One-way latency and throughput of a typed message between two service processes through the
embedded router (zenoh-python in router mode), as the services use it.

    python bench/bus_latency.py [--messages 5000] [--rate 1000] [--burst 50000]

Latency: a publisher process sends `VoiceCommand`s stamped with time.time() at a paced rate; a
subscriber process (validating each with pydantic, as every service does) records now - stamp.
Throughput: the publisher sends a burst as fast as it can; the subscriber counts what it received
per second of wall time between the first and the last message.
"""

from __future__ import annotations

import argparse
import multiprocessing as mp
import statistics
import time
from pathlib import Path

import zenoh

from schemas import Keys, VoiceCommand
from services.cli.router import Router, free_port, loopback_endpoint
from services.runtime import Credentials, ServiceContext, client_config


def _session(endpoint: str, creds: Path | None) -> zenoh.Session:
    return zenoh.open(client_config([endpoint], Credentials.load(creds) if creds else None))


def _subscriber(endpoint: str, robot: str, expect: int, ready: mp.Event, out: mp.Queue,
                creds: Path | None = None) -> None:
    ctx = ServiceContext("bench-sub", _session(endpoint, creds), Keys(robot))
    lat: list[float] = []
    times: list[float] = []

    def on_msg(msg: VoiceCommand) -> None:
        now = time.time()
        lat.append(now - msg.stamp)
        times.append(now)

    try:
        ctx.subscribe(ctx.keys.voice_command, VoiceCommand, on_msg)
        ready.set()
        deadline = time.monotonic() + 120
        while len(lat) < expect and time.monotonic() < deadline:
            time.sleep(0.05)
        time.sleep(0.2)
        out.put((lat, times))
    finally:
        ctx.close()


def _publisher(endpoint: str, robot: str, count: int, rate: float, start: mp.Event,
               creds: Path | None = None) -> None:
    ctx = ServiceContext("bench-pub", _session(endpoint, creds), Keys(robot))
    try:
        pub = ctx.publisher(ctx.keys.voice_command, VoiceCommand, block=True)
        start.wait(30)
        time.sleep(0.5)
        period = 1.0 / rate if rate > 0 else 0.0
        t0 = time.perf_counter()
        for i in range(count):
            if period:
                while time.perf_counter() < t0 + i * period:
                    time.sleep(period / 4)
            pub.put(VoiceCommand(command="go", text="go", confidence=0.9, engine="bench", stamp=time.time()))
        time.sleep(0.5)
    finally:
        ctx.close()


def run(count: int, rate: float, endpoint: str, robot: str,
        creds: tuple[Path | None, Path | None] = (None, None)) -> tuple[list[float], list[float]]:
    """`creds`: the subscriber's and the publisher's identity folders (None: anonymous)."""
    spawn = mp.get_context("spawn")  # never fork after a zenoh session exists
    ready, out = spawn.Event(), spawn.Queue()
    sub = spawn.Process(target=_subscriber, args=(endpoint, robot, count, ready, out, creds[0]))
    pub = spawn.Process(target=_publisher, args=(endpoint, robot, count, rate, ready, creds[1]))
    sub.start()
    pub.start()
    lat, times = out.get(timeout=180)
    pub.join(30)
    sub.join(30)
    return lat, times


def pct(values: list[float], q: float) -> float:
    return statistics.quantiles(values, n=1000)[int(q * 10) - 1] if len(values) > 1 else values[0]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--messages", type=int, default=5000)
    ap.add_argument("--rate", type=float, default=1000.0, help="paced rate for the latency run (msg/s)")
    ap.add_argument("--burst", type=int, default=50000, help="messages in the throughput run")
    args = ap.parse_args()
    endpoint = loopback_endpoint(free_port())
    with Router([endpoint]):
        lat, _ = run(args.messages, args.rate, endpoint, "benchlat")
        lat_ms = [x * 1000 for x in lat]
        print(f"latency   {len(lat)} VoiceCommand at {args.rate:.0f}/s, publisher -> router -> subscriber:")
        print(f"          p50 {pct(lat_ms, 50):.3f} ms   p99 {pct(lat_ms, 99):.3f} ms   max {max(lat_ms):.3f} ms")
        got, times = run(args.burst, 0, endpoint, "benchtput")
        span = times[-1] - times[0] if len(times) > 1 else float("nan")
        print(f"throughput {len(got)}/{args.burst} received, {len(got) / span:,.0f} messages/s "
              f"(validated with pydantic in the receiver)")


if __name__ == "__main__":
    main()
