"""A person's "stop" said just after the robot's sentence: end of speech -> `VoiceCommand`, through the running voice
service, while its echo canceller fits the way again (prints figures; not a test).

Each time a stretch of the robot's voice ends, the canceller fits the way from the loudspeaker to the microphone again
on its memory, on a thread of its own (`EchoCanceller.background`; 0.2-0.6 s, `bench/voice_echo_fit.py`). A "stop"
said then is heard while that thread runs beside the stream's. This bench measures what the person waits for, as the
robot's processes run:

- a router, the real speech service (`HRI_SPEECH_OUT`: its WAVs, no sound card), and the voice service as a process
  reading its stream from stdin (`HRI_VOICE_SOURCE=stdin`, every other setting its default), fed by a simulated
  microphone (`services/voice/simmic.py`: 30 ms blocks at a microphone's pace, a faint hiss);
- the bench asks the speech service to say one of the reasoner's sentences; from the moment the speech service says
  it began, the microphone hears it through a loudspeaker and room (`voice_own.EchoPath`, drawn once per run) at
  `--peak` dBFS, then a person's "stop" (espeak-ng, one of `STOP_VOICES`) at `--person` dBFS, begun one of `--gaps`
  seconds after the sentence's echo ends (30 dB under its loudest);
- latency: from the moment the microphone hands over the block holding the word's last sample (30 dB under its
  loudest) to the `VoiceCommand` "stop" arriving at the bench's session on the bus. A sound card hands a block over
  once its last sample is captured, so the word ended up to 30 ms before that. Only a "stop" that arrived once the
  block holding the word's first sample was handed over is the person's; one before it is the robot's own voice heard
  as "stop" (`self_stops`; since stop 96).

Each condition runs in a voice service of its own with a fresh state folder: `fitted` (the default, `HRI_VOICE_ECHO_FIT`
on), `not fitted` (off: no fit runs), and `alone` (the same "stop"s with no sentence before them). Per "stop" it
records whether a fit was put in use for that sentence (health's `echo_fits`) and how long it took, and whether that
fit may have run while the word was being decided (the fit from the first block past the filter's reach after the
echo, for the fit's time; the decision from the word's end to the command). Settings in the environment reach the
services (e.g. `HRI_VOICE_VAD_RESET=1`). `--busy` runs that many processes doing matrix products beside it (one thread
each), as another program on the robot's computer would.

    .venv/bin/python bench/voice_stop_latency.py --n 24
    .venv/bin/python bench/voice_stop_latency.py --n 24 --busy 1 --json out.json
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from bench.voice_bench import speech_end_s  # noqa: E402
from bench.voice_levels import at_level  # noqa: E402
from bench.voice_own import EchoPath, agent_sentences  # noqa: E402
from schemas.messages import Command, SpeechRequest, SpeechState, VoiceCommand  # noqa: E402
from services.cli.rig import service_rig  # noqa: E402
from services.voice import synth  # noqa: E402
from services.voice.audio import SAMPLE_RATE, to_pcm  # noqa: E402
from services.voice.echo import FILTER_S, LEAD_S  # noqa: E402
from services.voice.simmic import MixingMicrophone  # noqa: E402
from services.voice.training.tts import wav_samples  # noqa: E402

STOP_VOICES = (("en+f3", 140), ("en-us", 150), ("en+m3", 130), ("en-gb", 160))
"""espeak-ng voices and rates (words a minute) of the person's "stop" (the tuning family: the bench measures time, not
accuracy)."""
CONDITIONS = {"fitted": {"HRI_VOICE_ECHO_FIT": "on"}, "not fitted": {"HRI_VOICE_ECHO_FIT": "off"}, "alone": {}}
BUSY = ("import numpy as np\n"
        "a = np.random.default_rng(0).random((400, 400))\n"
        "while True:\n    a @ a\n")


@dataclass
class Trial:
    gap_s: float | None
    """How long after the sentence's echo ended the "stop" began (None: no sentence)."""
    latency_ms: float | None = None
    """End of the word -> the first `VoiceCommand` "stop" that arrived once the word had begun (None: not heard within
    8 s)."""
    self_stops: int = 0
    """"Stop"s that arrived before the word began: the robot's own voice heard as "stop", which the service publishes
    (a person's "stop" over the robot's voice must stop it). Until stop 96 the bench took the first "stop" after the
    sentence was asked for as the person's, so one such "stop" made the next trials take each person's word for the
    trial before's (round voice51b)."""
    fitted: bool = False
    """A fit was put in use after this sentence."""
    fit_ms: float | None = None
    during_fit: bool = False
    """That fit may have been running while the word was being decided (between its end and the command)."""


@dataclass
class Condition:
    name: str
    trials: list[Trial] = field(default_factory=list)

    def row(self) -> dict[str, object]:
        lat = np.array([t.latency_ms for t in self.trials if t.latency_ms is not None])
        during = np.array([t.latency_ms for t in self.trials if t.latency_ms is not None and t.during_fit])
        fits = [t.fit_ms for t in self.trials if t.fitted and t.fit_ms is not None]

        def pct(a: np.ndarray, q: float) -> float | None:
            return round(float(np.percentile(a, q)), 1) if a.size else None

        return {"condition": self.name, "stops": len(self.trials), "heard": int(lat.size),
                "self_stops": sum(t.self_stops for t in self.trials),
                "p50_ms": pct(lat, 50), "p90_ms": pct(lat, 90), "max_ms": pct(lat, 100),
                "decided_during_a_fit": int(during.size), "during_p50_ms": pct(during, 50),
                "during_max_ms": pct(during, 100), "fits": len(fits),
                "fit_ms_median": round(float(np.median(fits)), 1) if fits else None}


def wait_until(test: object, timeout: float) -> bool:
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        if test():  # type: ignore[operator]
            return True
        time.sleep(0.02)
    return False


def stops() -> list[np.ndarray]:
    return [synth.speak("stop", voice, rate) for voice, rate in STOP_VOICES]


def run_condition(name: str, n: int, gaps: list[float], peak: float, person: float, seed: int,
                  log: Path) -> Condition:
    """`n` "stop"s heard by a voice service of its own (`CONDITIONS[name]`), the gaps in turn."""
    rng = np.random.default_rng(seed)
    path = EchoPath.draw(rng, (0.2, 0.6))
    pick = np.random.default_rng(seed + 1)  # the sentences (`rng` draws each echo's delay, on the bus's thread)
    sentences, words = agent_sentences(), stops()
    out = Condition(name)
    with tempfile.TemporaryDirectory(prefix="voice-stop-") as tmp, open(log, "ab") as logf, \
            service_rig("bench", HRI_SPEECH_OUT=f"{tmp}/said", HRI_STATE_DIR=f"{tmp}/state",
                        HRI_VOICE_SOURCE="stdin", **CONDITIONS[name]) as rig:
        said = Path(tmp) / "said"
        heard: list[tuple[float, VoiceCommand]] = []
        rig.ctx.subscribe(rig.ctx.keys.voice_command, VoiceCommand, lambda c: heard.append((time.time(), c)))
        rig.start("speech", logf)
        voice = rig.start("voice", logf, stdin=subprocess.PIPE)
        mic = MixingMicrophone(voice)
        try:
            planned: dict[str, tuple[np.ndarray, float]] = {}

            def on_state(state: SpeechState) -> None:
                if not (state.speaking and state.id in planned):
                    return
                word, gap = planned.pop(state.id)
                said_x = wav_samples((said / f"{state.id}.wav").read_bytes())
                echo, _ = path.echo(said_x, rng)
                echo *= 10 ** (peak / 20) / path.peak(said_x)
                with mic.lock:
                    start = mic.mix(echo, 0.0)
                    echo_end = start + int(speech_end_s(to_pcm(np.clip(echo, -1, 1))) * SAMPLE_RATE)
                    begin = mic.mix(word, (echo_end - mic.handed) / SAMPLE_RATE + gap)
                    mic.marks[f"{state.id}:echo"] = echo_end
                    mic.marks[f"{state.id}:begin"] = begin
                    mic.marks[f"{state.id}:stop"] = begin + int(speech_end_s(to_pcm(word)) * SAMPLE_RATE)

            rig.ctx.subscribe(rig.ctx.keys.speech_state, SpeechState, on_state)
            if not wait_until(lambda: (h := rig.ctx.query_health("voice")) is not None
                              and "spotter_embedding" in h.detail, 90):
                raise SystemExit(f"the voice service did not come up: see {log}")
            time.sleep(2.0)  # the stream's clock settles on the least-delayed blocks (`clock.StreamClock`)
            fits, say = 0, rig.ctx.publisher(rig.ctx.keys.speech_say, SpeechRequest)
            for k in range(n):
                gap = gaps[k % len(gaps)]
                word = at_level(words[k % len(words)], person)
                ident = f"{name.replace(' ', '-')}-{k}"
                since = len(heard)
                if name == "alone":
                    with mic.lock:
                        begin = mic.mix(word, 0.3)
                        mic.marks[f"{ident}:begin"] = begin
                        mic.marks[f"{ident}:stop"] = begin + int(speech_end_s(to_pcm(word)) * SAMPLE_RATE)
                else:
                    planned[ident] = (word, gap)
                    say.put(SpeechRequest(text=sentences[int(pick.integers(len(sentences)))], id=ident))

                def stops_after(begun: float | None, since: int = since) -> list[float]:
                    """When each "stop" arrived once the word had begun (`begun`: None, not yet)."""
                    return [t for t, c in heard[since:]
                            if c.command is Command.STOP and begun is not None and t >= begun]

                wait_until(lambda ident=ident: stops_after(mic.times.get(f"{ident}:begin")), 8.0)
                time.sleep(1.5)  # the fit after the sentence, and the memory kept, are done
                trial = Trial(None if name == "alone" else gap)
                ended, begun = mic.times.get(f"{ident}:stop"), mic.times.get(f"{ident}:begin")
                got = stops_after(begun)
                trial.self_stops = sum(c.command is Command.STOP for _, c in heard[since:]) - len(got)
                if ended is not None and got:
                    trial.latency_ms = round((got[0] - ended) * 1000.0, 1)
                health = rig.ctx.query_health("voice")
                if health is not None and name != "alone":
                    now = int(health.detail.get("echo_fits", 0))
                    trial.fitted, fits = now > fits, now
                    trial.fit_ms = health.detail.get("echo_fit_ms_last") if trial.fitted else None
                    echo_end = mic.times.get(f"{ident}:echo")
                    if trial.fitted and trial.fit_ms is not None and echo_end is not None and ended is not None and got:
                        fit_from = echo_end + FILTER_S - LEAD_S  # the first block past the filter's reach
                        trial.during_fit = fit_from <= got[0] and ended <= fit_from + trial.fit_ms / 1000.0
                out.trials.append(trial)
                print(f"{name} {k}: {asdict(trial)}", flush=True)
        finally:
            mic.close()
    return out


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--n", type=int, default=24, help="\"stop\"s per condition")
    ap.add_argument("--gaps", default="0,0.15,0.3", help="seconds from the echo's end to the \"stop\", in turn")
    ap.add_argument("--peak", type=float, default=-12.0, help="the robot's voice at the microphone, dBFS peak")
    ap.add_argument("--person", type=float, default=-20.0, help="the person's \"stop\", dBFS peak")
    ap.add_argument("--conditions", default=",".join(CONDITIONS), help="of: " + ", ".join(CONDITIONS))
    ap.add_argument("--busy", type=int, default=0, help="processes doing matrix products beside it")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--log", type=Path, default=Path(tempfile.gettempdir()) / "voice_stop_latency.log",
                    help="the services' output")
    ap.add_argument("--json", type=Path)
    args = ap.parse_args()
    gaps = [float(g) for g in args.gaps.split(",")]
    names = [c.strip() for c in args.conditions.split(",") if c.strip()]
    if unknown := [c for c in names if c not in CONDITIONS]:
        ap.error(f"unknown conditions {unknown}: of {list(CONDITIONS)}")
    env = {**os.environ, "OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"}
    busy = [subprocess.Popen([sys.executable, "-c", BUSY], env=env) for _ in range(args.busy)]
    rows = []
    try:
        for name in names:
            rows.append(run_condition(name, args.n, gaps, args.peak, args.person, args.seed, args.log).row())
    finally:
        for proc in busy:
            proc.kill()
            proc.wait()
    print(f"# {os.cpu_count()} CPUs, {args.busy} busy beside; robot's voice {args.peak} dBFS, "
          f"person {args.person} dBFS; gaps {gaps} s")
    for row in rows:
        print(json.dumps(row))
    if args.json:
        args.json.write_text(json.dumps({"args": {k: str(v) for k, v in vars(args).items()}, "rows": rows}, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
