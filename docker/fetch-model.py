"""Fetch a zipped speech model, check its SHA-256 and unpack it (the Docker image's vosk model).

    python fetch-model.py URL SHA256 DEST

An empty URL skips the model (exit 0, one line saying so): no model URL may be reachable where the
image is built, and the default voice engine (pocketsphinx) ships its own model. A checksum mismatch
exits 1 and unpacks nothing.
"""

from __future__ import annotations

import hashlib
import shutil
import sys
import tempfile
import urllib.request
import zipfile
from pathlib import Path


def main(url: str, sha256: str, dest: Path) -> int:
    if not url:
        print(f"model skipped (empty URL): nothing at {dest}")
        return 0
    digest = hashlib.sha256()
    with tempfile.TemporaryDirectory() as tmp:
        archive = Path(tmp) / "model.zip"
        with urllib.request.urlopen(url, timeout=120) as response, archive.open("wb") as out:
            while chunk := response.read(1 << 20):
                digest.update(chunk)
                out.write(chunk)
        if digest.hexdigest() != sha256.lower():
            print(f"error: {url} has SHA-256 {digest.hexdigest()}, expected {sha256}", file=sys.stderr)
            return 1
        with zipfile.ZipFile(archive) as z:
            z.extractall(Path(tmp) / "x")  # zipfile drops absolute paths and '..' components
        tops = list((Path(tmp) / "x").iterdir())
        shutil.move(str(tops[0] if len(tops) == 1 and tops[0].is_dir() else Path(tmp) / "x"), dest)
    print(f"model from {url} (SHA-256 checked) in {dest}")
    return 0


if __name__ == "__main__":
    if len(sys.argv) != 4:
        sys.exit(__doc__)
    sys.exit(main(sys.argv[1], sys.argv[2], Path(sys.argv[3])))
