import sys, numpy as np, time
sys.argv=['x']
from bench.voice_bench import Item
from bench.voice_walking import pick, heldout_items, mix, OTHER, WORDS, SAMPLE_RATE, to_pcm, LEAD_S, TAIL_S, CHUNK
from bench.ego_noise import ego_noise, EgoNoiseModel
from services.voice.engine import make_engine
from services.voice.segmenter import Segmenter, SegmenterConfig
from services.voice.synth import noise
import webrtc_noise_gain as w, pyrnnoise
eng = make_engine("spotter")
clips = pick(heldout_items(1, 2), int(sys.argv[1]) if len(sys.argv) > 1 else 6, 1)
def webrtc(level):
    def f(pcm):
        ap = w.AudioProcessor(0, level)
        out = bytearray()
        for i in range(0, len(pcm) - 319, 320):
            out += ap.Process10ms(pcm[i:i+320]).audio
        return bytes(out) + b"\0" * (len(pcm) - len(out))
    return f
def rnn(pcm):
    d = pyrnnoise.RNNoise(16000)
    x = np.frombuffer(pcm, "<i2")
    out = np.concatenate([np.ravel(a) for _, a in d.denoise_chunk(x, partial=True)]).astype(np.int16)
    out = np.concatenate([out, np.zeros(max(0, x.size - out.size), np.int16)])[: x.size]
    return out.tobytes()
FRONTS = {"none": lambda p: p, "webrtc2": webrtc(2), "webrtc3": webrtc(3), "rnnoise": rnn}
def run(front, kind, snr, feed_raw):
    rng = np.random.default_rng(7)
    ok = n = oo = on = 0; lens = []
    for it in clips:
        sp = np.frombuffer(it.pcm, "<i2") / 32768.0
        at = int(LEAD_S * SAMPLE_RATE); secs = LEAD_S + sp.size / SAMPLE_RATE + TAIL_S; L = int(secs * SAMPLE_RATE)
        if kind == "walk": z = ego_noise(secs, rng)[:L]
        else: z = noise(kind, L, rng); z = z / np.sqrt(np.mean(z ** 2))
        raw = to_pcm(np.clip(mix(sp, z, snr, at), -1, 1))
        clean = FRONTS[front](raw)
        seg = Segmenter(SegmenterConfig()); segs = []
        for k in range(0, len(clean), CHUNK): segs += seg.feed(clean[k:k+CHUNK])
        segs += seg.flush()
        ws, we = LEAD_S, LEAD_S + sp.size / SAMPLE_RATE
        cmd = None; conf = 0
        for s in segs:
            lens.append(s.end_s - s.start_s)
            if s.start_s < we and s.end_s > ws:
                src = raw if feed_raw else clean
                pcm = src[int(s.start_s * SAMPLE_RATE) * 2: int(s.end_s * SAMPLE_RATE) * 2]
                r = eng.recognise(pcm)
                if r.command is not None and r.confidence >= 0.5: cmd, conf = r.command, r.confidence; break
        if it.label < OTHER: n += 1; ok += cmd is not None and cmd.value == WORDS[it.label]
        else: on += 1; oo += cmd is not None
    return ok / n, oo / on, np.percentile(lens, 90) if lens else 0
for kind in ("walk", "white"):
    for snr in (20, 10, 5):
        for front in FRONTS:
            for feed_raw in ((False, True) if front != "none" else (True,)):
                t = time.time()
                a, o, l = run(front, kind, snr, feed_raw)
                print(f"{kind:6} {snr:3} {front:8} spotter<-{'raw' if feed_raw else 'den'}  acc {a:.3f} oov {o:.3f} seg p90 {l:.2f}s  ({time.time()-t:.0f}s)", flush=True)
