# thrustshape service: FastAPI + uvicorn, solver worker processes, SQLite job store in /data.
#   docker build -t thrustshape .
#   docker run -p 8000:8000 -v thrustshape-data:/data thrustshape
# Settings come from THRUSTSHAPE_* variables (e.g. -e THRUSTSHAPE_WORKERS=4 -e THRUSTSHAPE_API_KEY=...).
FROM python:3.11-slim AS build
ENV PIP_NO_CACHE_DIR=1 PIP_DISABLE_PIP_VERSION_CHECK=1
WORKDIR /src
COPY pyproject.toml README.md ./
COPY ocp ./ocp
COPY service ./service
COPY clients ./clients
RUN python -m venv /opt/venv && /opt/venv/bin/pip install --upgrade pip && /opt/venv/bin/pip install '.[flightlogs,xlsx]'

FROM python:3.11-slim
ENV PATH=/opt/venv/bin:$PATH \
    PYTHONDONTWRITEBYTECODE=1 \
    PYTHONUNBUFFERED=1 \
    THRUSTSHAPE_DB_PATH=/data/jobs.sqlite3
# a C compiler: the flat program's SQP functions and the simulator's step are compiled at run time and cached
# under /data/.cache/thrustshape (without one, CasADi's virtual machine evaluates them: same answers, slower)
RUN apt-get update && apt-get install -y --no-install-recommends gcc libc6-dev && rm -rf /var/lib/apt/lists/*
RUN useradd --system --uid 10001 --home-dir /data --shell /usr/sbin/nologin thrustshape \
    && mkdir -p /data && chown thrustshape:thrustshape /data
COPY --from=build /opt/venv /opt/venv
USER thrustshape
WORKDIR /data
VOLUME ["/data"]
EXPOSE 8000
HEALTHCHECK --interval=30s --timeout=5s --start-period=30s --retries=3 \
    CMD ["python", "-c", "import sys, urllib.request; sys.exit(urllib.request.urlopen('http://127.0.0.1:8000/healthz', timeout=4).status != 200)"]
CMD ["thrustshape", "serve", "--host", "0.0.0.0", "--port", "8000"]
