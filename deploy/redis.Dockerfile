# Redis from Debian's package, for deploy/compose.yaml (the same binary the cluster test runs).
FROM debian:12-slim
RUN apt-get update \
    && apt-get install -y --no-install-recommends redis-server \
    && rm -rf /var/lib/apt/lists/* \
    && mkdir -p /data && chown redis:redis /data
USER redis
WORKDIR /data
EXPOSE 6379
CMD ["redis-server", "/etc/isomesh/redis.conf"]
