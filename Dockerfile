# One image for all five services; docker-compose.yml picks the service per container.
FROM python:3.11-slim-bookworm

RUN apt-get update \
 && apt-get install -y --no-install-recommends espeak-ng alsa-utils libportaudio2 curl unzip \
 && rm -rf /var/lib/apt/lists/*

# The small English vosk model (about 41 MB) for HRI_VOICE_ENGINE=vosk; fetched at build time because
# no English model is installable from the package registries.
ARG VOSK_MODEL=vosk-model-small-en-us-0.15
RUN curl -fsSL -o /tmp/model.zip https://alphacephei.com/vosk/models/${VOSK_MODEL}.zip \
 && unzip -q /tmp/model.zip -d /opt \
 && mv /opt/${VOSK_MODEL} /opt/vosk-model-en \
 && rm /tmp/model.zip
ENV HRI_VOSK_MODEL=/opt/vosk-model-en

WORKDIR /app
COPY pyproject.toml README.md ./
COPY schemas ./schemas
COPY services ./services
RUN pip install --no-cache-dir ".[mic]"

ENV PYTHONUNBUFFERED=1 \
    HRI_ZENOH_CONNECT=tcp/zenoh:7447 \
    HRI_STATE_DIR=/var/lib/hri
VOLUME ["/var/lib/hri"]
CMD ["hri", "--help"]
