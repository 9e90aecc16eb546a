"""Recording and preview costs: the MCAP recorder's throughput, the file size per minute of a running
robot, and the CPU the preview image costs the vision process.

1. writer: messages a second that `McapWriter` validates and writes (in process, no bus), for the
   biggest messages (preview, joints) and a small one (marks);
2. recorder: `McapRecorder` on a router fed by a publisher in another process as fast as it can
   publish MarkObservations; recorded messages a second (and how many were lost, if any);
3. robot: the simulated robot (five services) recorded for --robot-seconds while the paper's
   scenario runs (then idle if it ends sooner); bytes per minute in total and per key;
4. preview: the vision service (synthetic camera, 15 fps) for --cpu-seconds without a preview
   subscriber and --cpu-seconds with one: its CPU% both ways, and make_preview's own time per frame.

Prints one JSON object. Numbers are noisy on a loaded machine: say what else ran.
"""

from __future__ import annotations

import json
import multiprocessing as mp
import os
import statistics
import tempfile
import threading
import time
import uuid
from pathlib import Path
from typing import Annotated, Any

import numpy as np
import typer
import zenoh

from schemas.keys import Keys
from schemas.messages import Header, Mark, MarkObservation, Shape, VisionPreview
from services.cli.mcapfile import McapWriter
from services.cli.record import McapRecorder, without_images
from services.cli.rig import service_rig
from services.cli.scenario import load
from services.cli.simrobot import simulated_robot
from services.motion.joints import SIT
from services.motion.present import joint_positions
from services.runtime import ServiceContext, client_config
from services.vision.preview import PreviewSettings, make_preview
from services.vision.synthetic import MILD, SceneGenerator

TICK = os.sysconf("SC_CLK_TCK")


def cpu_seconds(pid: int) -> float:
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / TICK


def _frames(n: int) -> list[np.ndarray]:
    """Distinct camera frames (a recording of identical frames would compress far better than life)."""
    gen = SceneGenerator(seed=3, variation=MILD)
    return [gen.render(gen.scene(Shape.X if i % 2 else None))[0] for i in range(n)]


def bench_writer(n: int) -> dict[str, Any]:
    mark = Mark(shape=Shape.X, confidence=0.9, box=(200, 120, 240, 240))
    rng = np.random.default_rng(0)
    samples: dict[str, list[Header]] = {
        "vision/preview": [make_preview(f, i, [mark], time.time(), PreviewSettings())
                           for i, f in enumerate(_frames(40))],
        "motion/joints": [joint_positions({k: round(v) + int(rng.integers(-30, 30)) for k, v in SIT.items()})
                          for _ in range(200)],
        "vision/marks": [MarkObservation(marks=[mark] if i % 3 else [], frame=i) for i in range(200)],
    }
    out: dict[str, Any] = {}
    with tempfile.TemporaryDirectory() as tmp:
        for topic, msgs in samples.items():
            payloads = [m.model_dump_json().encode() for m in msgs]
            model = type(msgs[0])
            path = Path(tmp) / f"{topic.replace('/', '_')}.mcap"
            w = McapWriter(path)
            t0 = time.perf_counter()
            for i in range(n):
                data = payloads[i % len(payloads)]
                m = model.model_validate_json(data)  # as the recorder does
                m.stamp += i
                w.write(f"hri/bench/{topic}", m, data)
            w.close()
            dt = time.perf_counter() - t0
            out[topic] = {"message_bytes": round(statistics.mean(len(p) for p in payloads)),
                          "messages_per_s": round(n / dt),
                          "file_bytes_per_message": round(path.stat().st_size / n, 1)}
    return out


def _flood(endpoint: str, robot: str, seconds: float, ready: Any, sent: Any) -> None:
    """In another process: publish MarkObservations as fast as possible for `seconds`."""
    ctx = ServiceContext("flood", zenoh.open(client_config([endpoint])), Keys(robot))
    try:
        pub = ctx.publisher(ctx.keys.vision_marks, MarkObservation, block=True)
        while not pub.matched:
            time.sleep(0.01)
        ready.set()
        mark = Mark(shape=Shape.O, confidence=0.8, box=(10, 10, 50, 50))
        end = time.monotonic() + seconds
        n = 0
        while time.monotonic() < end:
            n += 1
            pub.put(MarkObservation(marks=[mark], frame=n))
        sent.value = n
    finally:
        ctx.close()


def bench_recorder(seconds: float) -> dict[str, Any]:
    robot = f"b{uuid.uuid4().hex[:8]}"
    with service_rig(robot, participant="bench") as rig, tempfile.TemporaryDirectory() as tmp:
        rec = McapRecorder(rig.ctx, Path(tmp) / "flood.mcap")
        spawn = mp.get_context("spawn")
        ready, sent = spawn.Event(), spawn.Value("q", 0)
        proc = spawn.Process(target=_flood, args=(rig.endpoint, robot, seconds, ready, sent))
        proc.start()
        ready.wait(30)
        t0 = time.monotonic()
        proc.join(seconds + 30)
        last = -1
        while rec.summary.messages != last:  # what is still in flight or queued arrives and is written
            last = rec.summary.messages
            time.sleep(1.0)
        dt = time.monotonic() - t0 - 1.0
        summary = rec.close()
        recorded = summary.messages
        return {"published": sent.value, "recorded": recorded, "seconds": round(dt, 2),
                "recorded_per_s": round(recorded / dt), "file_bytes": summary.size_bytes,
                "file_bytes_per_message": round(summary.size_bytes / max(recorded, 1), 1)}


def bench_robot(seconds: float) -> dict[str, Any]:
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp)
        path = out / "robot.mcap"
        with simulated_robot(out, robot=f"b{uuid.uuid4().hex[:8]}", participant="bench") as sim:
            missing = sim.runner.wait_ready(timeout=90)
            if missing:
                raise SystemExit(f"robot did not come up: {missing}")
            rec = McapRecorder(sim.ctx, path)
            lean = McapRecorder(sim.ctx, out / "no-images.mcap", without_images(sim.ctx.keys))
            t0 = time.monotonic()
            sim.runner.run(load("paper"))
            scenario_s = time.monotonic() - t0
            left = seconds - (time.monotonic() - t0)
            if left > 0:
                time.sleep(left)
            summary, lean_summary = rec.close(), lean.close()
        minutes = summary.duration_s / 60
        per_key = {k.split("/", 2)[2]: {"messages_per_min": round(c / minutes),
                                        "json_bytes_per_min": round(summary.payload_bytes[k] / minutes)}
                   for k, c in sorted(summary.counts.items())}
        return {"seconds": round(summary.duration_s, 1), "scenario_s": round(scenario_s, 1),
                "messages": summary.messages, "file_bytes": summary.size_bytes,
                "file_bytes_per_min": round(summary.size_bytes / minutes),
                "file_bytes_per_min_without_images": round(lean_summary.size_bytes / minutes),
                "json_bytes_per_min": round(sum(summary.payload_bytes.values()) / minutes),
                "messages_per_min": round(summary.messages / minutes), "per_key": per_key}


def bench_preview_cpu(seconds: float) -> dict[str, Any]:
    frame = _frames(1)[0]
    times = []
    for _ in range(200):
        t0 = time.perf_counter()
        p = make_preview(frame, 1, [], 0.0, PreviewSettings())
        times.append(time.perf_counter() - t0)
    result: dict[str, Any] = {"frame": f"{frame.shape[1]}x{frame.shape[0]}",
                              "make_preview_ms_p50": round(statistics.median(times) * 1000, 2),
                              "preview_bytes": len(p.model_dump_json())}
    robot = f"b{uuid.uuid4().hex[:8]}"
    with service_rig(robot, participant="bench", HRI_VISION_SOURCE="synthetic:none") as rig:
        frames: list[float] = []
        rig.ctx.subscribe(rig.ctx.keys.vision_marks, MarkObservation, lambda m: frames.append(time.monotonic()))
        proc = rig.start("vision")
        deadline = time.monotonic() + 60
        while len(frames) < 30 and time.monotonic() < deadline:
            time.sleep(0.1)
        time.sleep(2.0)  # past start-up

        def cpu_over(s: float) -> tuple[float, float]:
            c0, t0, f0 = cpu_seconds(proc.pid), time.monotonic(), len(frames)
            time.sleep(s)
            dt = time.monotonic() - t0
            return 100 * (cpu_seconds(proc.pid) - c0) / dt, (len(frames) - f0) / dt

        off, fps_off = cpu_over(seconds)
        got: list[VisionPreview] = []
        lock = threading.Lock()

        def on_preview(p: VisionPreview) -> None:
            with lock:
                got.append(p)

        viewer = ServiceContext("viewer", zenoh.open(client_config([rig.endpoint])), rig.ctx.keys)
        try:
            viewer.subscribe(viewer.keys.vision_preview, VisionPreview, on_preview)
            time.sleep(2.0)
            n0 = len(got)
            on, fps_on = cpu_over(seconds)
            previews_per_s = (len(got) - n0) / seconds
        finally:
            viewer.close()
    result.update({"vision_cpu_pct_without_viewer": round(off, 1), "vision_cpu_pct_with_viewer": round(on, 1),
                   "camera_fps": round(fps_off, 1), "camera_fps_with_viewer": round(fps_on, 1),
                   "previews_per_s": round(previews_per_s, 1)})
    return result


def main(
    writer_n: Annotated[int, typer.Option(help="messages per kind for the writer")] = 5000,
    flood_seconds: Annotated[float, typer.Option(help="seconds of flooding for the recorder")] = 5.0,
    robot_seconds: Annotated[float, typer.Option(help="seconds of the running robot to record")] = 60.0,
    cpu_seconds_each: Annotated[float, typer.Option("--cpu-seconds", help="seconds per preview CPU window")] = 20.0,
    parts: Annotated[str, typer.Option(help="comma-separated: writer, recorder, robot, preview")]
    = "writer,recorder,robot,preview",
) -> None:
    chosen = {p.strip() for p in parts.split(",")}
    out: dict[str, Any] = {"load_avg_at_start": os.getloadavg()[0]}
    if "writer" in chosen:
        out["writer"] = bench_writer(writer_n)
    if "recorder" in chosen:
        out["recorder"] = bench_recorder(flood_seconds)
    if "robot" in chosen:
        out["robot"] = bench_robot(robot_seconds)
    if "preview" in chosen:
        out["preview"] = bench_preview_cpu(cpu_seconds_each)
    out["load_avg_at_end"] = os.getloadavg()[0]
    print(json.dumps(out, indent=2))


if __name__ == "__main__":
    typer.run(main)
