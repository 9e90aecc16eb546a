"""End-to-end figures across the five real processes on the simulated OP2.

    python bench/system_latency.py [--commands 20] [--stops 8] [--vision-fps 30]

- command -> servo: a `VoiceCommand` published (as the voice service would) to the first SYNC_WRITE on
  the simulated bus carrying the resulting motion (`MotionState.first_write`, stamped by the motion
  service when the driver writes it), alternating "yes" (nod) and "no" (shake) while standing;
- X shown -> halted: the synthetic camera (30 fps by default, `--vision-fps`) starts showing an X
  while the robot walks, at a random phase of its frame clock (1 s plus up to one frame period after
  walking began: the robot's own messages, and so a fixed wait, can be in step with the frames);
  time to the first frame reported with the confirmed X (its exposure), to the reasoner's
  `stop` goal, to the first servo write of that goal, and to the
  robot standing still in double support (walking ends at the next half-cycle boundary);
- spoken -> heard: a synthesised WAV dropped in the voice spool to its `VoiceCommand`;
- the resident memory (RSS) of the launcher with its router and the five services.

Each figure is printed as p50, p90 and p99 (of n samples: with 25 stops the p99 is the slowest one).
"""

from __future__ import annotations

import argparse
import os
import random
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

from schemas import Action, Posture, SceneCommand, Shape, VoiceCommand
from schemas.keys import SERVICES
from services.cli.simrobot import SimulatedRobot, simulated_robot
from services.cli.utterance import speak_into


def rss_mib(pid: int) -> float:
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith("VmRSS:"):
            return int(line.split()[1]) / 1024
    return 0.0


def pcts(xs: list[float]) -> str:
    xs = sorted(xs)
    if not xs:
        return "no samples"
    p = lambda q: xs[min(len(xs) - 1, int(round(q * (len(xs) - 1))))]  # noqa: E731
    return (f"p50 {p(0.5) * 1000:7.1f} ms   p90 {p(0.9) * 1000:7.1f} ms   p99 {p(0.99) * 1000:7.1f} ms   "
            f"(n={len(xs)}, max {xs[-1] * 1000:.1f} ms)")


@dataclass
class Figures:
    """Samples in seconds, and resident memory per process in MiB."""

    cmd: list[float]
    seen: list[float]
    stop_goal: list[float]
    stop_write: list[float]
    halted: list[float]
    heard: list[float]
    rss: dict[str, float]
    vision: dict[str, object]  # the vision service's health detail at the end (frames per second, ...)


def measure(sim: SimulatedRobot, args: argparse.Namespace) -> Figures:
    """Drive the robot through the three experiments and read its memory."""
    launcher, ctx, rec, runner, out = sim.launcher, sim.ctx, sim.rec, sim.runner, sim.out
    voice = ctx.publisher(ctx.keys.voice_command, VoiceCommand)
    scene = ctx.publisher(ctx.keys.vision_scene, SceneCommand)

    def say(word: str) -> float:
        stamp = time.time()
        voice.put(VoiceCommand(command=word, text=word, confidence=0.99, engine="bench", stamp=stamp))
        return stamp

    def settle(posture: Posture, timeout: float = 15.0) -> bool:
        return bool(rec.wait(lambda: (s := rec.latest_state) and s.posture == posture and
                             (s.action is None or posture == Posture.WALKING), timeout))

    missing = runner.wait_ready(90)
    if missing:
        raise SystemExit(f"robot did not come up: {missing}; logs in {out / 'services.log'}")
    time.sleep(2.0)
    say("stand")
    settle(Posture.STANDING)

    cmd_lat: list[float] = []
    for i in range(args.commands):
        word, action = ("yes", Action.NOD) if i % 2 == 0 else ("no", Action.SHAKE_HEAD)
        t_mono = time.monotonic()
        stamp = say(word)
        goal = rec.wait(lambda: next((g for g in rec.since(t_mono, "goal") if g.action == action), None), 5)
        state = goal and rec.wait(lambda: next((s for s in rec.since(t_mono, "motion")
                                                if s.goal_id == goal.goal_id and s.first_write), None), 5)
        if state:
            cmd_lat.append(state.first_write - stamp)
        settle(Posture.STANDING)

    seen_lat, stop_goal_lat, stop_write_lat, halted_lat = [], [], [], []
    phase = random.Random(args.seed)
    for _ in range(args.stops):
        scene.put(SceneCommand(shape=Shape.O))
        time.sleep(0.6)
        scene.put(SceneCommand(shape=None))
        say("go")
        if not settle(Posture.WALKING):
            continue
        time.sleep(1.0 + phase.uniform(0.0, 1.0 / args.vision_fps))
        t_mono = time.monotonic()
        shown = time.time()
        scene.put(SceneCommand(shape=Shape.X))
        obs = rec.wait(lambda: next((o for o in rec.since(t_mono, "seen")
                                     if any(m.shape == Shape.X for m in o.marks)), None), 5)
        goal = rec.wait(lambda: next((g for g in rec.since(t_mono, "goal") if g.action == Action.STOP), None), 5)
        stop_state = goal and rec.wait(lambda: next((s for s in rec.since(t_mono, "motion")
                                                     if s.goal_id == goal.goal_id and s.first_write), None), 5)
        halted = rec.wait(lambda: next((e for e in rec.events if e.t >= t_mono and e.kind == "motion"
                                        and e.msg.posture == Posture.STANDING and e.msg.action is None), None), 5)
        if obs:
            seen_lat.append(obs.stamp - shown)
        if goal:
            stop_goal_lat.append(goal.stamp - shown)
        if stop_state:
            stop_write_lat.append(stop_state.first_write - shown)
        if halted:
            halted_lat.append(halted.msg.stamp - shown)
        scene.put(SceneCommand(shape=None))
        time.sleep(0.5)

    heard_lat = []
    for i in range(args.utterances):
        t_mono = time.monotonic()
        t_wall = time.time()
        speak_into(out / "spool", "yes" if i % 2 == 0 else "no")
        heard = rec.wait(lambda: next(iter(rec.since(t_mono, "heard")), None), 10)
        if heard:
            heard_lat.append(heard.stamp - t_wall)
        settle(Posture.STANDING)

    health = ctx.query_health("vision")
    vision = dict(health.detail) if health is not None else {}
    pids = {n: launcher.pid(n) for n in SERVICES}
    rss = {n: rss_mib(p) for n, p in pids.items() if p}
    rss["launcher+router"] = rss_mib(os.getpid())
    return Figures(cmd_lat, seen_lat, stop_goal_lat, stop_write_lat, halted_lat, heard_lat, rss, vision)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--commands", type=int, default=20)
    ap.add_argument("--stops", type=int, default=8)
    ap.add_argument("--utterances", type=int, default=8)
    ap.add_argument("--vision-fps", type=float, default=30.0, help="the synthetic camera's frame rate")
    ap.add_argument("--seed", type=int, default=0, help="the random phases at which the X is shown")
    args = ap.parse_args()
    out = Path(tempfile.mkdtemp(prefix="hri-bench-"))
    env = {"HRI_LOG_LEVEL": "warning", "HRI_VISION_FPS": f"{args.vision_fps:g}"}
    with simulated_robot(out, robot="bench", participant="bench", env=env) as sim:
        f = measure(sim, args)
    print(f"command published -> first servo write carrying it:  {pcts(f.cmd)}")
    print(f"X shown -> frame reported with confirmed X:           {pcts(f.seen)}")
    print(f"X shown -> stop goal published by the reasoner:       {pcts(f.stop_goal)}")
    print(f"X shown -> first servo write of the stop goal:        {pcts(f.stop_write)}"
          f"   ({args.vision_fps:g} fps camera)")
    print(f"X shown -> standing still (double support):           {pcts(f.halted)}")
    print(f"WAV in spool -> VoiceCommand published:               {pcts(f.heard)}")
    v = f.vision
    print(f"vision at the end: {v.get('fps')} frames per second published, detection {v.get('detect_ms_mean')} ms a"
          f" frame (mean), looked ahead {v.get('lookahead_looks', 'n/a')}, published ahead for danger"
          f" {v.get('lookahead_dangers', 'n/a')}")
    print("resident memory (MiB): " + ", ".join(f"{n} {v:.0f}" for n, v in f.rss.items())
          + f"; total {sum(f.rss.values()):.0f}")
    print(f"(the bench process hosts the launcher and router; logs in {out / 'services.log'})")


if __name__ == "__main__":
    main()
