"""Episodic-memory cost of the reasoner: decision latency, memory and store size over a long run.

    .venv/bin/python bench/reasoner_episodes.py [--inputs 100000] [--bound-mb 16] [--baseline]

The Soar agent in this process (no Zenoh: the agent's own cost), its episodes in a file with the
service's settings (committed per episode, rotated at `--bound-mb`). Inputs cycle through a mix
like a session's: the six commands (go at sure and unsure confidences, yes answering questions),
marks that change the situation (X, O) and marks that do not, and a "why" every 1,000 inputs.
Every input is one step (queued, pumped until the agent settles).

- latency: input queued -> Decision out of the agent (the output callback), per window of
  10,000 inputs, p50 / p99 / max; the "why"s: input queued -> explanation out (two epmem
  retrievals over the whole store).
- memory: resident set size (VmRSS) per window; epmem's own SQLite memory (`epmem --stats`).
- store: bytes of episodes.db (+ episodes.db.1, the one older generation) against the bound.
`--baseline` runs the same inputs with episodic memory off (learning off): the cost without it.
Figures on a shared 2-core machine are noisy; compare runs made under the same load.
"""

from __future__ import annotations

import statistics
import sys
import tempfile
import time
from pathlib import Path
from typing import Annotated

import typer

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from services.reasoner.agent_host import (  # noqa: E402
    AgentConfig,
    CommandInput,
    DecisionOutput,
    Event,
    ExplanationOutput,
    MarksInput,
    Output,
    SoarAgent,
)

# One round of a session: 20 inputs (18 decisions: the repeated X and O change nothing).
ROUND: list[Event | str] = [
    CommandInput("stand", 0.9), "standing", CommandInput("yes", 0.9), CommandInput("no", 0.9),
    CommandInput("go", 0.95), "walking", CommandInput("stop", 0.9), "standing",
    CommandInput("go", 0.6), CommandInput("yes", 0.8), "walking", MarksInput(frozenset({"X"})),
    "standing", MarksInput(frozenset({"X"})), CommandInput("go", 0.9), MarksInput(frozenset({"O"})),
    "walking", MarksInput(frozenset({"O"})), CommandInput("down", 0.9), "sitting",
    CommandInput(None, 0.2), CommandInput("down", 0.9),
]


def vm_rss_mb() -> float:
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith("VmRSS:"):
            return int(line.split()[1]) / 1024
    return float("nan")


def pct(values: list[float], q: float) -> float:
    ordered = sorted(values)
    return ordered[min(len(ordered) - 1, int(q * len(ordered)))]


def store_bytes(db: Path) -> tuple[int, int]:
    old = db.with_name(db.name + ".1")
    return (db.stat().st_size if db.exists() else 0, old.stat().st_size if old.exists() else 0)


def run(inputs: int, bound_mb: float, baseline: bool, folder: Path, window: int = 10_000) -> dict[str, object]:
    db = folder / "episodes.db"
    marks: dict[str, float] = {}

    def on_output(out: Output) -> None:
        if isinstance(out, DecisionOutput | ExplanationOutput) and "t" not in marks:
            marks["t"] = time.perf_counter()

    config = AgentConfig(episodes=None if baseline else db, episodes_max_bytes=int(bound_mb * 1024 * 1024))
    rows = []
    whys: list[float] = []
    with SoarAgent(config, on_output=on_output) as agent:
        if baseline:
            agent.execute("epmem --set learning off")
        lat: list[float] = []
        done = 0
        step = 0
        rss0 = vm_rss_mb()
        while done < inputs:
            item = ROUND[step % len(ROUND)]
            step += 1
            if isinstance(item, str):
                agent.step(posture=item)
                continue
            is_why = done % 1000 == 999
            event = CommandInput("why", 0.9) if is_why else item
            marks.clear()
            t0 = time.perf_counter()
            agent.submit(event)
            agent.pump()
            if "t" in marks:
                (whys if is_why else lat).append((marks["t"] - t0) * 1e3)
            done += 1
            if done % window == 0:
                size, old = store_bytes(db)
                rows.append({"inputs": done, "p50_ms": statistics.median(lat), "p99_ms": pct(lat, 0.99),
                             "max_ms": max(lat), "rss_mb": vm_rss_mb(), "store_mb": size / 2**20,
                             "old_mb": old / 2**20, "rotations": agent.episode_rotations})
                lat = []
        epmem_mem = agent.execute("epmem --stats mem-usage")[1].strip()
        episodes = agent.execute("epmem --stats time")[1].strip()
    return {"rows": rows, "whys": whys, "rss0": rss0, "epmem_mem": epmem_mem, "episodes_next": episodes}


def main(
    inputs: Annotated[int, typer.Option(help="Inputs to feed (commands and marks)")] = 100_000,
    bound_mb: Annotated[float, typer.Option(help="Rotation bound of the episodes file, MB")] = 16.0,
    baseline: Annotated[bool, typer.Option(help="Episodic memory off: the same run without its cost")] = False,
) -> None:
    with tempfile.TemporaryDirectory(prefix="hri-episodes-") as tmp:
        result = run(inputs, bound_mb, baseline, Path(tmp))
    mode = "episodic memory OFF (baseline)" if baseline else f"episodes in a file, bound {bound_mb:g} MB"
    print(f"reasoner episodes bench: {inputs} inputs, {mode}; RSS at start {result['rss0']:.1f} MB")
    print(f"{'inputs':>8} {'p50 ms':>8} {'p99 ms':>8} {'max ms':>8} {'RSS MB':>8} {'store MB':>9} {'old MB':>7} {'rot':>4}")
    for r in result["rows"]:  # type: ignore[union-attr]
        print(f"{r['inputs']:>8} {r['p50_ms']:>8.3f} {r['p99_ms']:>8.3f} {r['max_ms']:>8.1f} {r['rss_mb']:>8.1f} "
              f"{r['store_mb']:>9.2f} {r['old_mb']:>7.2f} {r['rotations']:>4}")
    whys = result["whys"]
    if whys:
        print(f"why (two epmem retrievals): {len(whys)} asked, p50 {statistics.median(whys):.2f} ms, "  # type: ignore[arg-type]
              f"max {max(whys):.2f} ms")  # type: ignore[arg-type]
    print(f"epmem SQLite memory at the end: {result['epmem_mem']} bytes; next episode {result['episodes_next']}")


if __name__ == "__main__":
    typer.run(main)
