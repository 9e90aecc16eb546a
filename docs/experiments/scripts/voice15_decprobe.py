"""Probe (tuning data only): Whisper tiny.en's decoder, one step after the prompt, as a second opinion.
For every clip of the tune splits: the shipped head's probabilities and the decoder's log-probs of each
command's tokens (4 spellings each) and of the best token overall."""
import sys, multiprocessing, numpy as np, ctranslate2, tokenizers
from services.voice.training import dataset
from services.voice.training.train import TUNE_SPLITS
from services.voice.spotter.whisper import WhisperEmbedder, FRAMES, DIM
from services.voice.spotter.features import centre
from services.voice.spotter.head import Head
from faster_whisper.tokenizer import Tokenizer

WORDS = ["stand", "down", "yes", "no", "go", "stop", "why"]
_S = {}
def setup():
    e = WhisperEmbedder()
    tok = Tokenizer(tokenizers.Tokenizer.from_file(str(e.path / "tokenizer.json")), False, task="transcribe", language="en")
    ids = [[tok.encode(v)[0] for v in (" " + w, " " + w.capitalize(), w.capitalize(), w)] for w in WORDS]
    _S.update(e=e, head=Head.load("services/voice/spotter/head.npz"), ids=ids, prompt=tok.sot_sequence + [tok.no_timestamps])

def decoder_logprobs(enc):
    e = _S["e"]
    view = ctranslate2.StorageView.from_array(np.ascontiguousarray(enc[None]))
    r = e._model.generate(view, [_S["prompt"]], max_length=2, beam_size=1, return_logits_vocab=True, suppress_blank=False)
    z = np.asarray(r[0].logits[0][0], dtype=np.float32).ravel()
    z = z - z.max(); lp = z - np.log(np.exp(z).sum())
    cmd = [float(np.logaddexp.reduce(lp[i])) for i in _S["ids"]]
    return np.array(cmd + [float(lp.max())], dtype=np.float32)

def one(r):
    if not _S: setup()
    try:
        pcm = dataset.render(r)
    except Exception:
        return None
    if pcm is None: return None
    enc = _S["e"].encode(centre(pcm, 0))
    feats = enc.reshape(FRAMES, -1, DIM).mean(axis=1)
    p = _S["head"].probabilities(feats)[0]
    return p.astype(np.float32), decoder_logprobs(enc)

if __name__ == "__main__":
    sizes = dataset.Sizes(); seed = 0
    from services.voice.training.train import TrainConfig
    cfg = TrainConfig(); sizes, seed = cfg.sizes, cfg.seed
    rows = []
    for sp in TUNE_SPLITS:
        for r in dataset.recipes(sp, sizes, seed): rows.append((sp, r))
    print(len(rows), flush=True)
    with multiprocessing.Pool(2) as pool:
        out = pool.map(one, [r for _, r in rows], chunksize=16)
    keep = [i for i, o in enumerate(out) if o is not None]
    np.savez("/work/scratch/w2/decprobe_tune.npz",
             p=np.stack([out[i][0] for i in keep]), d=np.stack([out[i][1] for i in keep]),
             y=np.array([rows[i][1].label for i in keep]), split=np.array([rows[i][0] for i in keep]),
             text=np.array([rows[i][1].text for i in keep]), voice=np.array([rows[i][1].voice for i in keep]))
    print("done", len(keep))
