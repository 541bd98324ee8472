# lodstudio's batch image: the release binary on a slim base.
#   docker build -t lodstudio:latest .
#   docker run --rm -v "$PWD/assets:/data" lodstudio:latest \
#     export /data/models --recipe /data/chain.json -o /data/lods --json
# The studio is in the same binary but needs a display; the image is for
# `lodstudio export` (and every other subcommand) headless.

FROM rust:1.95-slim-bookworm AS build
WORKDIR /src
COPY Cargo.toml Cargo.lock ./
COPY core core
COPY app app
COPY tests tests
COPY assets assets
RUN cargo build --release --locked -p lodstudio --bin lodstudio

FROM debian:bookworm-slim
# ca-certificates only for TLS mounts; no GPU or display libraries are needed
# for batch export (the GUI libraries are loaded only when the studio opens).
RUN apt-get update \
 && apt-get install -y --no-install-recommends ca-certificates \
 && rm -rf /var/lib/apt/lists/* \
 && useradd --create-home --uid 10001 lodstudio
COPY --from=build /src/target/release/lodstudio /usr/local/bin/lodstudio
USER lodstudio
ENTRYPOINT ["lodstudio"]
CMD ["--help"]
