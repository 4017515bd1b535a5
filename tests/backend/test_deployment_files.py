"""The shipped deployment (docker-compose.yml, Dockerfile) trusts no client to say who it is: only the reverse proxy
it ships in front of the server may set X-Forwarded-For, and the server publishes no port of its own."""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import yaml

ROOT = Path(__file__).resolve().parents[2]


def _compose() -> dict[str, Any]:
    return yaml.safe_load((ROOT / "docker-compose.yml").read_text())


def test_the_image_trusts_no_forwarding_proxy_by_default():
    dockerfile = (ROOT / "Dockerfile").read_text()
    (default,) = re.findall(r"COACH_FORWARDED_ALLOW_IPS:-([^}\"]*)", dockerfile)
    assert "*" not in default, "the image trusts every client's X-Forwarded-For"


def test_compose_puts_a_proxy_in_front_and_trusts_only_it():
    services = _compose()["services"]
    server, proxy = services["server"], services["proxy"]
    assert "ports" not in server, "the server publishes a port: clients could reach it past the proxy"
    assert {"80:80", "443:443"} <= {str(p) for p in proxy["ports"]}
    trusted = server["environment"]["COACH_FORWARDED_ALLOW_IPS"]
    proxy_ip = proxy["networks"]["coach"]["ipv4_address"]
    assert trusted == proxy_ip, f"the server trusts {trusted!r}, the proxy is {proxy_ip}"
    caddyfile = (ROOT / "deploy" / "Caddyfile").read_text()
    assert "reverse_proxy server:8000" in caddyfile and "flush_interval -1" in caddyfile  # events unbuffered


def test_compose_keeps_session_files_in_minio_with_its_bucket_made_at_start():
    services = _compose()["services"]
    server, init = services["server"], services["minio-init"]
    env = server["environment"]
    assert env["COACH_STORAGE_BACKEND"] == "s3" and env["COACH_S3_ENDPOINT_URL"] == "http://minio:9000"
    assert server["depends_on"]["minio-init"]["condition"] == "service_completed_successfully"
    assert "mc mb --ignore-existing" in " ".join(init["entrypoint"])
    assert "miniodata:/data" in services["minio"]["volumes"]
    assert "ports" not in services["minio"], "the object store is reached by the server only"


def test_compose_runs_a_worker_on_the_same_database_and_bucket():
    services = _compose()["services"]
    worker, server = services["worker"], services["server"]
    assert worker["command"] == ["coach-server", "worker"]
    for name in ("COACH_DATABASE_URL", "COACH_STORAGE_BACKEND", "COACH_S3_BUCKET", "COACH_S3_ENDPOINT_URL"):
        assert worker["environment"][name] == server["environment"][name], name


def test_the_retention_setting_reaches_the_service_the_daily_command_runs_in():
    """docs/deployment.md runs `docker compose exec -T server coach-server retention` daily: without the setting in
    the server's environment it would answer "retention is off" however .env sets it."""
    services = _compose()["services"]
    assert "exec -T server coach-server retention" in (ROOT / "docs" / "deployment.md").read_text()
    for name in ("server", "worker"):
        assert services[name]["environment"]["COACH_RETENTION_DAYS"] == "${COACH_RETENTION_DAYS:-0}", name
