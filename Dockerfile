# cellard in a container: built on Debian, run as a non-root user with the database on a volume.
#   docker build -t cellar .
#   docker run -p 8080:8080 -v cellar-data:/data cellar
FROM debian:12 AS build
RUN apt-get update && apt-get install -y --no-install-recommends \
        gcc make libc6-dev libjansson-dev libmicrohttpd-dev libsqlite3-dev libssl-dev libxml2-dev \
        libpq-dev \
    && rm -rf /var/lib/apt/lists/*
WORKDIR /src
COPY . .
RUN make build/cellard build/cellar

FROM debian:12-slim
RUN apt-get update && apt-get install -y --no-install-recommends \
        libjansson4 libmicrohttpd12 libsqlite3-0 libssl3 libxml2 libpq5 curl \
    && rm -rf /var/lib/apt/lists/* \
    && useradd --system --home /data --shell /usr/sbin/nologin cellar \
    && mkdir -p /data && chown cellar:cellar /data
COPY --from=build /src/build/cellard /src/build/cellar /usr/local/bin/
USER cellar
VOLUME /data
ENV CELLAR_LISTEN=0.0.0.0:8080 CELLAR_DB=/data/cellar.db
EXPOSE 8080
STOPSIGNAL SIGTERM
HEALTHCHECK --interval=10s --timeout=3s --start-period=5s \
    CMD curl -fsS http://127.0.0.1:8080/healthz || exit 1
ENTRYPOINT ["/usr/local/bin/cellard"]
