import numpy as np, subprocess, io, wave, itertools
from services.voice.segmenter import Segmenter, SegmenterConfig
from services.voice.engine import make_engine
from services.voice.audio import to_pcm
from scipy.signal import resample_poly
eng = make_engine("spotter")
phrases = ["All right, I will not walk.", "Shall I walk forward?", "Sorry, I cannot do it now.", "Sorry, I cannot do it.",
 "Sorry, I did not understand.", "I asked whether to walk, and you said no 3 seconds ago.",
 "I asked whether to walk, and you said yes 4 seconds ago.", "I asked whether to go, and you did not answer.",
 "I did not understand what you said.", "I had already done that when you said 'stand'.", "I have not decided anything yet.",
 "I saw an O 2 seconds ago, so it is safe to walk again.", "I saw an O, so I carried out the 'go' you gave me 5 seconds ago.",
 "I saw an X 3 seconds ago, and no O since. Show me an O and I will walk.", "I saw a triangle 2 seconds ago. I will not walk until I see an O.",
 "I stopped because I saw an X 1 second ago.", "I was not sure I heard 'go'.", "I was not sure I heard 'go', so I asked first.",
 "I was still moving when you said 'down': that must finish first."]
def say(t, voice="en-us", rate=160):
    out = subprocess.run(["espeak-ng", "-v", voice, "-s", str(rate), "--stdout", t], capture_output=True).stdout
    w = wave.open(io.BytesIO(out)); sr = w.getframerate()
    a = np.frombuffer(w.readframes(w.getnframes()), np.int16) / 32768.0
    return resample_poly(a, 16000, sr)
for vad in ("silero", "webrtc"):
    heard = []
    for t in phrases:
        x = np.concatenate([np.zeros(8000), say(t) * 0.5, np.zeros(16000)]) + np.random.default_rng(0).normal(0, 3e-4, 1)
        x = x + np.random.default_rng(1).normal(0, 3e-4, x.size)
        pcm = to_pcm(x); seg = Segmenter(SegmenterConfig(vad=vad)); segs = []
        for k in range(0, len(pcm), 960): segs += seg.feed(pcm[k:k+960])
        segs += seg.flush()
        for s in segs:
            r = eng.recognise(s.pcm)
            if r.command is not None:
                heard.append((t, round(s.end_s - s.start_s, 2), r.command.value, round(r.confidence, 2)))
    print(vad, len(heard), "commands heard in", len(phrases), "of the robot's own sentences")
    for h in heard: print("   ", h)
