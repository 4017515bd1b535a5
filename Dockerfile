# Kinect Home Coach coaching server.  Build: docker build -t kinect-home-coach .

# The browser's pose assets (MediaPipe Tasks Vision, BlazePose .task models): fetched with npm, checked against
# kinect_agent/vendor/lock.json (sha512 of each tarball, sha256 of each packed model) in a stage of their own.
FROM python:3.11-slim AS vendor
RUN apt-get update -qq && apt-get install -y -qq --no-install-recommends npm >/dev/null && rm -rf /var/lib/apt/lists/*
WORKDIR /src
COPY requirements/vendor.lock ./requirements/
RUN pip install --no-cache-dir --no-deps --require-hashes -r requirements/vendor.lock
COPY kinect_agent/__init__.py ./kinect_agent/
COPY kinect_agent/vendor ./kinect_agent/vendor
RUN python -m kinect_agent.vendor.install

FROM python:3.11-slim

ENV PYTHONDONTWRITEBYTECODE=1 \
    PYTHONUNBUFFERED=1 \
    PIP_NO_CACHE_DIR=1 \
    PIP_DISABLE_PIP_VERSION_CHECK=1 \
    COACH_HOST=0.0.0.0 \
    COACH_PORT=8000

WORKDIR /app
COPY requirements/server.lock ./requirements/
RUN pip install --require-hashes -r requirements/server.lock
# The server's distribution (packages/server/pyproject.toml): backend, the pages, the migrations, `coach-server`, and
# the part of kinect_agent the server imports; not the agent's services or CLI.
COPY packages/server ./packages/server
COPY kinect_agent ./kinect_agent
COPY --from=vendor /src/kinect_agent/vendor/files ./kinect_agent/vendor/files
COPY backend ./backend
COPY migrations ./migrations
COPY frontend ./frontend
RUN pip install --no-deps ./packages/server && rm -rf /app/*

RUN useradd --system --create-home --uid 10001 coach && mkdir -p /data && chown coach /data
USER coach
WORKDIR /data

EXPOSE 8000
HEALTHCHECK --interval=30s --timeout=5s --start-period=20s --retries=3 \
    CMD python -c "import urllib.request,sys; sys.exit(urllib.request.urlopen('http://127.0.0.1:8000/healthz').status != 200)"

# Make sure the object store's bucket exists, bring the schema to head (moving any stored blobs out), then serve (the server itself refuses a database behind head). X-Forwarded-For is
# trusted only from COACH_FORWARDED_ALLOW_IPS (docker-compose.yml: its proxy); by default from nobody else.
CMD ["sh", "-c", "coach-server storage init && coach-server migrate && exec coach-server serve --forwarded-allow-ips \"${COACH_FORWARDED_ALLOW_IPS:-127.0.0.1}\""]
