"""Round voice41c, tuning data only: why round voice41b's high-pass found more far words over a DC offset.

Round voice37's tuning clips (`voice37_tune.tune_items`: 40 of each command and 200 other words, train seed 12's tune
splits), each 1.2 s into its own stream at a speech peak in a quiet room's hiss (-70 dBFS), through a 48 kHz
microphone's path (`through_mic`), with an offset added, fed to the service's segmenter and the default engine (as
`voice41_dc_tune.py`). Each case is NAME:DC:HZ:FROM - the offset (fraction of full scale), the high-pass (Hz or off)
and `highpass_from_dbfs` (dBFS, or `none`: on from the first sample; -200: switched on half a second in, offset or
not). `--keep-vad-state` leaves out the VADs' restart at the switch (`SileroEndpointer.forget`), as round 41b had it;
`--subtract` (after round 41c's decision) takes the offset out at the switch by subtracting the stream's mean over the
second before it instead of the high-pass (the idea for a next round: the audio is then the clean microphone's, up to
rounding). `--lead` puts each word this far into its stream (the benches' 1.2 s; after the decision too: a live
stream switches once, the benches' streams put every word 0.7 s after their own switch).

    .venv/bin/python docs/experiments/scripts/voice41c_state_probe.py --peak -44 base:0:off:-50 \\
        latched:0.03:30:-50 forced:0:30:-200 always:0:30:none twin:0.0000152:off:-50

Prints one JSON row per case: commands heard, other words taken, false walks, words no segment covered.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[3]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from voice37_tune import tune_items, tuning_stream  # noqa: E402

from bench import voice_levels, voice_walking  # noqa: E402
from bench.voice_bench import Policy  # noqa: E402
from bench.voice_walking import run_streams  # noqa: E402
from services.voice.audio import from_pcm, to_pcm  # noqa: E402
from services.voice.engine import make_engine  # noqa: E402
from services.voice.segmenter import Segmenter, SegmenterConfig  # noqa: E402
from services.voice.vad import SileroEndpointer  # noqa: E402


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--cache", type=Path, default=Path("/tmp/s77/voice36_tune_clips.pickle"))
    ap.add_argument("--peak", type=float, default=-44.0)
    ap.add_argument("--keep-vad-state", action="store_true")
    ap.add_argument("--subtract", action="store_true")
    ap.add_argument("--lead", type=float, default=voice_walking.LEAD_S, help="seconds of hiss before each word")
    ap.add_argument("cases", nargs="+", help="NAME:DC:HZ:FROM")
    args = ap.parse_args()
    voice_levels.LEAD_S = voice_walking.LEAD_S = args.lead  # read by `in_room` and `run_streams`
    if args.keep_vad_state:
        SileroEndpointer.forget = lambda self: None  # type: ignore[method-assign]
    if args.subtract:
        seen = Segmenter._offset_seen

        def subtracted(self: Segmenter, pcm: bytes) -> bool:
            if not seen(self, pcm):
                return False
            mean = sum(v for v, *_ in self._offset) / sum(n for *_, n in self._offset) / 32768.0
            self._highpass = lambda chunk: to_pcm(from_pcm(chunk) - mean)  # type: ignore[assignment]
            return True

        Segmenter._offset_seen = subtracted  # type: ignore[method-assign]
    items = tune_items(args.cache, 40, 200, 37)
    engine, policy = make_engine("spotter"), Policy.from_knowledge()
    for case in args.cases:
        name, dc_text, hz, start = case.split(":")
        config = SegmenterConfig(highpass_hz=None if hz == "off" else float(hz),
                                 highpass_from_dbfs=None if start == "none" else float(start),
                                 highpass_dc_share=0.0)  # the switch as it was before round voice43
        dc = float(dc_text)

        def build(speech: np.ndarray, rng: np.random.Generator, dc: float = dc) -> np.ndarray:
            return tuning_stream(speech, args.peak, rng, dc)

        row = run_streams(engine, items, build, config, policy, 37)
        print(json.dumps({"case": name, "peak_dbfs": args.peak, "vad_restart": not args.keep_vad_state,
                          "subtract": args.subtract, "lead_s": args.lead,
                          **{k: row[k] for k in ("command_accuracy", "oov_accepted", "false_walks",
                                                 "no_segment_over_word")}}), flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
