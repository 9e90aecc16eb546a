# One image for all five services; docker-compose.yml picks the service per container.
FROM python:3.11-slim-bookworm

# espeak-ng: the speech service's voice (and `python -m services.voice say`); alsa-utils: aplay for a
# speaker; libportaudio2: microphones (the `mic` extra).
RUN apt-get update \
 && apt-get install -y --no-install-recommends espeak-ng alsa-utils libportaudio2 \
 && rm -rf /var/lib/apt/lists/*

# The small English vosk model (about 41 MB) for HRI_VOICE_ENGINE=vosk, fetched at build time because no
# English model is installable from the package registries; its SHA-256 is checked. Point VOSK_MODEL_URL
# at a mirror with --build-arg (and VOSK_MODEL_SHA256 at its checksum for another model), or set it empty
# to build without it: the default engine, pocketsphinx, ships its own model.
ARG VOSK_MODEL_URL=https://alphacephei.com/vosk/models/vosk-model-small-en-us-0.15.zip
ARG VOSK_MODEL_SHA256=30f26242c4eb449f948e42cb302dd7a686cb29a3423a8367f99ff41780942498
COPY docker/fetch-model.py /tmp/fetch-model.py
RUN python /tmp/fetch-model.py "$VOSK_MODEL_URL" "$VOSK_MODEL_SHA256" /opt/vosk-model-en && rm /tmp/fetch-model.py
ENV HRI_VOSK_MODEL=/opt/vosk-model-en

# Dependencies first (from pyproject.toml), so that a code change rebuilds only the last layers.
WORKDIR /app
COPY pyproject.toml ./
RUN python -c 'import tomllib; p = tomllib.load(open("pyproject.toml", "rb"))["project"]; \
print("\n".join(p["dependencies"] + p["optional-dependencies"]["mic"]))' > /tmp/requirements.txt \
 && pip install --no-cache-dir -r /tmp/requirements.txt \
 && rm /tmp/requirements.txt
COPY README.md ./
COPY schemas ./schemas
COPY services ./services
RUN pip install --no-cache-dir --no-deps ".[mic]"

# The services run as an unprivileged user, in the groups that own sound, camera and serial devices.
# Their state lives in /var/lib/hri; the folders made here (the voice spool among them) are copied into
# a fresh named volume the first time it is mounted.
RUN useradd --uid 10001 --user-group --no-create-home --home-dir /var/lib/hri --shell /usr/sbin/nologin \
      --groups audio,video,dialout hri \
 && mkdir -p /var/lib/hri/voice-spool /var/lib/hri/speech /var/lib/hri/reasoner \
 && chown -R hri:hri /var/lib/hri
USER hri

# Each container runs as the identity whose folder is mounted at /run/secrets/hri (docker-compose.yml).
ENV PYTHONUNBUFFERED=1 \
    HRI_ZENOH_CONNECT=tls/zenoh:7447 \
    HRI_CREDENTIALS=/run/secrets/hri \
    HRI_STATE_DIR=/var/lib/hri
VOLUME ["/var/lib/hri"]
CMD ["hri", "--help"]
