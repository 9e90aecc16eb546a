"""Training of the command spotter's head: synthesised speech from several offline TTS engines, many
negatives, augmentation, a small classifier. Run with `python -m services.voice train` (never in CI)."""
