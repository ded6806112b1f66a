# HAProxy from Debian's package, for deploy/compose.yaml and deploy/k8s (the same binary the
# cluster test runs).
FROM debian:12-slim
RUN apt-get update \
    && apt-get install -y --no-install-recommends haproxy \
    && rm -rf /var/lib/apt/lists/*
USER haproxy
EXPOSE 8080
CMD ["haproxy", "-db", "-f", "/etc/isomesh/haproxy.cfg"]
