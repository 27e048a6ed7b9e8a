# syntax=docker/dockerfile:1
# twostep in a container: the locked environment and the data; the demo by default.
#
#   docker build -t twostep --build-arg TWOSTEP_VERSION=0.2.0 .
#   docker run --rm twostep                 # make demo
#   docker run --rm twostep make test       # the fast test suite
#
# x86_64 only: Fast Downward has no Linux ARM wheel; on an ARM host build and run with
# --platform linux/amd64 (emulated). See docs/install.md.
FROM python:3.11-slim-bookworm

# uv installed the uv way: the static binary from its official image, the version the
# Makefile pins (UV_VERSION).
COPY --from=ghcr.io/astral-sh/uv:0.13.8 /uv /uvx /usr/local/bin/

# make runs the project's commands; nothing else is needed from Debian.
# hadolint ignore=DL3008
RUN apt-get update \
    && apt-get install -y --no-install-recommends make \
    && rm -rf /var/lib/apt/lists/*

# An unprivileged user owns the checkout, the environment, the outputs and ~/.cache (made
# here: the build's cache mount below would otherwise leave it to root, unwritable at run time).
RUN useradd --create-home --uid 1000 twostep \
    && mkdir /home/twostep/app /home/twostep/.cache \
    && chown 1000:1000 /home/twostep/app /home/twostep/.cache
USER 1000:1000
WORKDIR /home/twostep/app

# The image's Python, never a downloaded one; files copied out of uv's cache, which is a
# build cache mount and stays out of the image.
ENV UV_PYTHON_DOWNLOADS=never \
    UV_LINK_MODE=copy \
    UV_CACHE_DIR=/home/twostep/.cache/uv

# Dependencies first, in a layer of their own: a change to the code does not reinstall them.
COPY --chown=1000:1000 pyproject.toml uv.lock Makefile ./
RUN --mount=type=cache,target=/home/twostep/.cache/uv,uid=1000,gid=1000 make deps

# No .git in the image: the version comes from the build argument (setuptools-scm).
ARG TWOSTEP_VERSION=0.0.0
COPY --chown=1000:1000 . .
RUN --mount=type=cache,target=/home/twostep/.cache/uv,uid=1000,gid=1000 \
    SETUPTOOLS_SCM_PRETEND_VERSION_FOR_TWOSTEP="$TWOSTEP_VERSION" make setup

CMD ["make", "demo"]
