# dualrep as a container: `docker compose up` (see README, "Deploy").
#
# Build stage: a release build of the one binary. No `-C target-cpu=native`: the image must run
# on any x86-64 host, and the numeric kernels pick their CPU features at run time.
FROM rust:1.95-bookworm AS build
WORKDIR /src
COPY . .
# The registry and target caches survive between builds (BuildKit), so a code change does not
# rebuild the dependencies.
RUN --mount=type=cache,target=/usr/local/cargo/registry \
    --mount=type=cache,target=/src/target \
    cargo build --release --locked --bin dualrep \
    && cp target/release/dualrep /usr/local/bin/dualrep

# Runtime stage: the binary (it carries the web UI and the shipped experts), run as an
# unprivileged user.
FROM debian:bookworm-slim
# ca-certificates for outgoing TLS (a remote Rerun viewer); curl for the compose health check.
RUN apt-get update \
    && apt-get install -y --no-install-recommends ca-certificates curl \
    && rm -rf /var/lib/apt/lists/*
RUN useradd --system --create-home --home-dir /home/dualrep --shell /usr/sbin/nologin dualrep \
    && mkdir -p /data \
    && chown dualrep:dualrep /data
COPY --from=build /usr/local/bin/dualrep /usr/local/bin/dualrep
WORKDIR /home/dualrep
USER dualrep
# SQLite database, checkpoints and recordings (<data-dir>/recordings/<session-id>.rrd).
VOLUME ["/data"]
EXPOSE 8080
ENTRYPOINT ["dualrep"]
CMD ["serve", "--addr", "0.0.0.0:8080", "--data-dir", "/data"]
