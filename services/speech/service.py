"""The speech service: `SpeechRequest` in, espeak-ng audio out, `SpeechState` around each utterance.

Threads: Zenoh's subscriber thread only checks a request and queues it; one worker speaks the
queue in order; the service's main loop re-checks a missing engine or sound device and keeps
`Health` current.
"""

from __future__ import annotations

import threading
import time
from collections import deque

from schemas.messages import HealthStatus, SpeechRequest, SpeechState
from services.runtime import ServiceContext
from services.speech.config import SpeechConfig, default_folder
from services.speech.player import AplayOutput, FolderOutput, Output, PlaybackError
from services.speech.queue import SpeechQueue, Utterance
from services.speech.stats import SpeechStats
from services.speech.text import TextRejected, clean_text
from services.speech.tts import INSTALL_HINT, EngineMissing, EspeakNg, Synthesis, SynthesisError

NAME = "speech"
ENGINE_RETRY_S = 2.0
"""How often a missing or failing espeak-ng is checked again."""
OUTPUT_RETRY_S = 5.0
"""How often an unusable sound device or folder is checked again."""
RECENT_IDS = 256
"""A request id seen among the last this-many requests is a duplicate and is not spoken twice."""


class SpeechService:
    def __init__(self, ctx: ServiceContext, config: SpeechConfig) -> None:
        self.ctx = ctx
        self.config = config
        self.log = ctx.log
        self.tts = EspeakNg(config.voice, config.rate, config.volume)
        target = config.output_for(ctx.robot)
        self.fallback = FolderOutput(target.folder or default_folder(ctx.robot))
        self.output: Output = AplayOutput(target.device) if target.device is not None else self.fallback
        self.queue = SpeechQueue(config.queue_size, config.max_age_s)
        self.stats = SpeechStats()
        self.state = ctx.publisher(ctx.keys.speech_state, SpeechState)
        self._engine_error: str | None = "not checked yet"
        self._output_error: str | None = "not checked yet"
        self._recent: deque[str] = deque(maxlen=RECENT_IDS)
        self._recent_lock = threading.Lock()
        ctx.update_detail(
            engine="espeak-ng",
            voice=config.voice,
            rate=config.rate,
            volume=config.volume,
            out=self.output.describe(),
            queue_size=config.queue_size,
            max_age_s=config.max_age_s,
            max_chars=config.max_chars,
        )

    # ------------------------------------------------------------------ health
    @property
    def engine_ready(self) -> bool:
        return self._engine_error is None

    @property
    def output_ok(self) -> bool:
        return self._output_error is None

    def check_engine(self) -> None:
        try:
            version = self.tts.check()
        except (EngineMissing, SynthesisError) as exc:
            if str(exc) != self._engine_error:
                self.log.error("speech engine unusable, will retry", error=str(exc), retry_s=ENGINE_RETRY_S)
            self._engine_error = str(exc)
        else:
            if self._engine_error is not None:
                self.log.info("speech engine ready", engine=version, voice=self.config.voice)
                self.ctx.update_detail(engine=version)
            self._engine_error = None

    def check_output(self) -> None:
        problem = self.output.probe()
        if problem != self._output_error:
            if problem is None:
                self.log.info("speech output ready", out=self.output.describe())
            elif self.output is self.fallback:
                self.log.error("speech output unusable, will retry",
                               out=self.output.describe(), error=problem)
            else:
                self.log.warning(
                    "sound device unusable, writing WAV files instead; will retry",
                    device=self.output.describe(), error=problem, fallback=self.fallback.describe(),
                )
        self._output_error = problem

    def _publish_status(self) -> None:
        detail = {
            "engine_error": self._engine_error,
            "output_error": self._output_error,
            "install": INSTALL_HINT if self._engine_error else None,
        }
        nowhere = self._output_error is not None and self.output is self.fallback
        if self._engine_error is not None or nowhere:
            self.ctx.set_status(HealthStatus.FAILED, **detail)  # nothing can be said, or nowhere to put it
        elif self._output_error is not None:
            alternatives = (
                f"HRI_SPEECH_OUT=<folder> to write WAV files; now writing to {self.fallback.folder}"
            )
            self.ctx.set_status(HealthStatus.DEGRADED, device=self.output.describe(),
                                alternatives=alternatives, **detail)
        else:
            self.ctx.set_status(HealthStatus.OK, **detail)

    def _report(self) -> None:
        self.ctx.update_detail(
            queued=len(self.queue),
            dropped_full=self.queue.dropped_full,
            dropped_stale=self.queue.dropped_stale,
            **self.stats.summary(),
        )

    # ------------------------------------------------------------------ requests
    def on_request(self, req: SpeechRequest) -> None:
        """Subscriber callback: check and queue; never blocks on speech."""
        received = time.monotonic()
        try:
            text = clean_text(req.text, self.config.max_chars)
        except TextRejected as exc:
            self.stats.bump("rejected_text")
            self.ctx.counters.bump("rejected")
            self.log.warning("rejected speech request", id=req.id, reason=str(exc))
            self._report()
            return
        if not self.engine_ready:
            self.stats.bump("rejected_unavailable")
            self.log.error("cannot speak: engine unusable", id=req.id, text=text, error=self._engine_error)
            self._report()
            return
        with self._recent_lock:
            if req.id in self._recent:
                self.stats.bump("duplicates")
                self.log.warning("duplicate speech request ignored", id=req.id)
                return
            self._recent.append(req.id)
        dropped = self.queue.put(Utterance(req.id, text, received=received, stamp=req.stamp))
        if dropped is not None:
            self.log.warning("speech queue full, dropped the oldest request", id=dropped.utterance.id,
                             text=dropped.utterance.text, waited_s=round(dropped.age_s, 3),
                             queue_size=self.queue.maxsize)
        self.log.debug("queued", id=req.id, queued=len(self.queue))
        self._report()

    # ------------------------------------------------------------------ speaking
    def speak_queue(self) -> None:
        """Worker: speak queued utterances one at a time, in order, until stopping."""
        while not self.ctx.stopping.is_set():
            utt, skipped = self.queue.take(timeout=0.2)
            for s in skipped:
                self.log.warning("skipped stale speech request", id=s.utterance.id, text=s.utterance.text,
                                 waited_s=round(s.age_s, 3), max_age_s=self.queue.max_age_s)
            if skipped:
                self._report()
            if utt is None:
                continue
            try:
                self.speak(utt)
            except Exception:  # the worker must outlive any one utterance
                self.stats.bump("synth_errors")
                self.log.exception("speaking failed", id=utt.id)
            self._report()

    def speak(self, utt: Utterance) -> None:
        output = self.output if self.output_ok else self.fallback
        try:
            audio = self.tts.synthesize(utt.text, output.path_for(utt.id))
        except EngineMissing as exc:
            self._engine_error = str(exc)
            self._publish_status()
            self.stats.bump("rejected_unavailable")
            self.log.error("cannot speak: engine gone", id=utt.id, error=str(exc))
            return
        except SynthesisError as exc:
            self.stats.bump("synth_errors")
            self.log.error("synthesis failed", id=utt.id, text=utt.text, error=str(exc))
            return
        ready_ms = (time.monotonic() - utt.received) * 1000.0
        self.stats.ready(ready_ms)
        self.log.info("speaking", id=utt.id, text=utt.text, duration_s=round(audio.duration_s, 3),
                      ready_ms=round(ready_ms, 1), synth_ms=round(audio.synth_s * 1000, 1),
                      out=output.describe(), file=str(audio.path) if output is self.fallback else None)
        # In health too: a listener that subscribes mid-sentence (the voice service starting) asks for it.
        self.ctx.update_detail(speaking=True, speaking_id=utt.id)
        self.state.put(SpeechState(speaking=True, id=utt.id, text=utt.text))
        try:
            finished = self._play(output, audio, utt)
        finally:
            self.ctx.update_detail(speaking=False, speaking_id=None)
            self.state.put(SpeechState(speaking=False, id=utt.id, text=utt.text))
        self.stats.bump("spoken" if finished else "interrupted")
        if not finished:
            self.log.info("utterance cut short by shutdown", id=utt.id)

    def _play(self, output: Output, audio: Synthesis, utt: Utterance) -> bool:
        try:
            return output.play(audio, self.ctx.stopping)
        except PlaybackError as exc:
            self._output_error = str(exc)
            self._publish_status()
            self.log.warning("playback failed, writing the WAV instead", id=utt.id, error=str(exc))
            return self.fallback.play(self.fallback.adopt(audio, utt.id), self.ctx.stopping)

    # ------------------------------------------------------------------ lifecycle
    def run(self) -> None:
        self.check_engine()
        self.check_output()
        self._publish_status()
        self.log.info("speech output", out=self.output.describe(),
                      fallback=None if self.output is self.fallback else self.fallback.describe(),
                      note="folder output: speaking lasts the WAV's duration after it is written")
        worker = self.ctx.thread(self.speak_queue, "speak")
        self.ctx.subscribe(self.ctx.keys.speech_say, SpeechRequest, self.on_request)
        self.ctx.update_detail(speaking=False, speaking_id=None)
        self.state.put(SpeechState(speaking=False))  # listening now; and "not speaking" after a restart
        next_engine = time.monotonic() + ENGINE_RETRY_S
        next_output = time.monotonic() + OUTPUT_RETRY_S
        try:
            while not self.ctx.wait(0.25):
                now = time.monotonic()
                if not self.engine_ready and now >= next_engine:
                    self.check_engine()
                    self._publish_status()
                    next_engine = now + ENGINE_RETRY_S
                if not self.output_ok and now >= next_output:
                    self.check_output()
                    self._publish_status()
                    next_output = now + OUTPUT_RETRY_S
        finally:
            worker.join(timeout=5.0)  # it publishes speaking=False before the session closes
            self.output.close()
            left = self.queue.clear()
            if left:
                self.log.info("stopped with requests unspoken", ids=[u.id for u in left])


def serve(ctx: ServiceContext, config: SpeechConfig | None = None) -> None:
    SpeechService(ctx, config or SpeechConfig()).run()
