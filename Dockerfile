# cellard in a container: built on Debian, run as a non-root user with its database on a volume.
#   podman build --format docker -t cellar .     (docker build -t cellar . works the same)
#   podman run -d -p 127.0.0.1:8080:8080 -v cellar-data:/data cellar
# README, "Deploying with containers", says more (variables, volumes, a read-only root, the
# compose stack); tests/t_containers.sh builds and runs this image in `make test`.
# The build stage also needs node and npm: the page cellard serves is bundled from web/ with
# three.js and esbuild from npm (web/package-lock.json) and embedded in the binary; the runtime
# stage has no node.
FROM debian:12 AS build
RUN apt-get update && apt-get install -y --no-install-recommends \
        gcc make libc6-dev libjansson-dev libmicrohttpd-dev libsqlite3-dev libssl-dev libxml2-dev \
        libpq-dev zlib1g-dev libzip-dev nodejs npm ca-certificates \
    && rm -rf /var/lib/apt/lists/*
WORKDIR /src
COPY . .
# Behind a proxy that re-signs TLS, npm needs the proxy's CA: give it as the build secret "ca"
# (podman build --secret id=ca,src=/path/to/ca.pem ..., docker the same); without it, none.
RUN --mount=type=secret,id=ca \
    if [ -s /run/secrets/ca ]; then export NODE_EXTRA_CA_CERTS=/run/secrets/ca; fi; \
    make build/cellard build/cellar

# The runtime holds only the libraries cellard links (ldd build/cellard): libjansson4 (JSON),
# libmicrohttpd12 (HTTP), libsqlite3-0 (the embedded store), libpq5 (the PostgreSQL store),
# libssl3 (SHA-256 of requests and results), libxml2 (SVG and 3MF), libzip4 (3MF packages);
# zlib1g (gzip) is in every Debian
# image already.  No curl: the HEALTHCHECK is
# cellard --healthcheck.
FROM debian:12-slim
RUN apt-get update && apt-get install -y --no-install-recommends \
        libjansson4 libmicrohttpd12 libsqlite3-0 libssl3 libxml2 libpq5 libzip4 \
    && rm -rf /var/lib/apt/lists/* /var/cache/apt/* /usr/share/doc/* /usr/share/man/* \
    && useradd --system --home /data --shell /usr/sbin/nologin cellar \
    && mkdir -p /data && chown cellar:cellar /data
COPY --from=build /src/build/cellard /src/build/cellar /usr/local/bin/
ARG VERSION=0.3.0
ARG SOURCE=unknown
LABEL org.opencontainers.image.title="cellar" \
      org.opencontainers.image.description="cellular arrangements as a service: LAR complexes and Booleans of 2D drawings and 3D solids" \
      org.opencontainers.image.version="${VERSION}" \
      org.opencontainers.image.source="${SOURCE}" \
      org.opencontainers.image.licenses="MIT"
USER cellar
VOLUME /data
ENV CELLAR_LISTEN=0.0.0.0:8080 CELLAR_DB=/data/cellar.db
EXPOSE 8080
STOPSIGNAL SIGTERM
HEALTHCHECK --interval=10s --timeout=3s --start-period=5s \
    CMD ["/usr/local/bin/cellard", "--healthcheck"]
ENTRYPOINT ["/usr/local/bin/cellard"]
