"""Installs the pinned browser assets and pose models of lock.json into kinect_agent/vendor/files/ (hash-checked).

    python -m kinect_agent.vendor.install [--relock] [--quiet]

For each npm package: `npm pack NAME@VERSION` (no install scripts run), the tarball's sha512 checked against the
lock's integrity, and only the members that lock.json serves or packs unpacked. Then each `.task` is packed from the
models (input-normalisation metadata added, kinect_agent.vendor.tflite_metadata) and its SHA-256 checked against the
lock. A second run with everything in place only reads a stamp and returns. Exit status 1 with one line on a missing
npm, a network failure or a hash mismatch; nothing half-written is left in files/. --relock writes the hashes found
into lock.json instead of refusing them (for a maintainer bumping a version, who reviews the diff).
"""

from __future__ import annotations

import argparse
import base64
import hashlib
import json
import os
import shutil
import subprocess
import sys
import tarfile
import tempfile
from collections.abc import Callable
from pathlib import Path
from typing import Any

from kinect_agent.vendor import FILES, LOCK_PATH, VendorError, all_served_files, load_lock, package_dir

STAMP = FILES / ".installed"
NPM_TIMEOUT_S = 600


def sha512_integrity(data: bytes) -> str:
    """Returns the npm/SRI integrity string of data ("sha512-" + base64 digest)."""
    return "sha512-" + base64.b64encode(hashlib.sha512(data).digest()).decode()


def _lock_digest() -> str:
    return hashlib.sha256(LOCK_PATH.read_bytes()).hexdigest()


def is_installed(lock: dict[str, Any]) -> bool:
    """Returns whether the stamp matches this lock file and every served file is present."""
    try:
        stamp = STAMP.read_text(encoding="utf-8").strip()
    except OSError:
        return False
    return stamp == _lock_digest() and all(p.is_file() for p in all_served_files(lock).values())


def _needed_members(lock: dict[str, Any], name: str) -> set[str]:
    """Returns the paths inside npm package `name` that are served or packed into a `.task`."""
    prefix = f"npm/{name}/"
    served = (rel for table in lock["serve"].values() for rel in table.values())
    members = {rel[len(prefix) :] for rel in served if rel.startswith(prefix)}
    for task in lock["tasks"]:
        for part in (task["detector"], task["landmarks"]):
            if part["package"] == name:
                members.add(part["path"])
    members.add("package.json")
    return members


def npm_pack(name: str, version: str, dest: Path) -> bytes:
    """Returns the bytes of the registry tarball of name@version, fetched with `npm pack`; raises VendorError."""
    npm = shutil.which("npm")
    if npm is None:
        raise VendorError("npm is needed to fetch the pinned browser assets (Debian: apt-get install npm)")
    cmd = [npm, "pack", f"{name}@{version}", "--json", "--ignore-scripts", "--pack-destination", str(dest)]
    try:
        done = subprocess.run(cmd, capture_output=True, text=True, timeout=NPM_TIMEOUT_S, check=False)
    except subprocess.TimeoutExpired as exc:
        raise VendorError(f"npm pack {name}@{version} did not finish in {NPM_TIMEOUT_S} s") from exc
    if done.returncode != 0:
        last = (done.stderr.strip().splitlines() or ["no message"])[-1]
        raise VendorError(f"npm pack {name}@{version} failed: {last}")
    try:
        filename = json.loads(done.stdout)[0]["filename"]
    except (ValueError, LookupError, TypeError) as exc:
        raise VendorError(f"npm pack {name}@{version} printed no tarball name") from exc
    return (dest / filename).read_bytes()


def _unpack(tarball: bytes, members: set[str], target: Path) -> None:
    """Unpacks the wanted members of an npm tarball (prefix package/) into target, replacing it whole."""
    tmp = Path(tempfile.mkdtemp(prefix=".unpack-", dir=target.parent))
    try:
        with tempfile.TemporaryFile() as f:
            f.write(tarball)
            f.seek(0)
            with tarfile.open(fileobj=f, mode="r:gz") as tar:
                found = set()
                for info in tar.getmembers():
                    rel = info.name.removeprefix("package/")
                    if rel in members and info.isfile():
                        info.name = rel
                        tar.extract(info, tmp, filter="data")
                        found.add(rel)
        missing = members - found
        if missing:
            raise VendorError(f"{target.name}: the tarball has no {', '.join(sorted(missing))}")
        tmp.chmod(0o755)  # mkdtemp's 0700 would hide the files from a server running as another user
        for path in tmp.rglob("*"):
            path.chmod(0o644 if path.is_file() else 0o755)
        if target.exists():
            shutil.rmtree(target)
        tmp.rename(target)
    finally:
        if tmp.exists():
            shutil.rmtree(tmp)


def install_packages(lock: dict[str, Any], *, relock: bool, log: Callable[[str], None]) -> None:
    """Fetches, checks and unpacks every npm package whose unpacked copy is missing or of another version."""
    for package in lock["npm"]:
        name, version, integrity = package["name"], package["version"], package["integrity"]
        target = package_dir(name)
        marker = target / ".integrity"
        if marker.is_file() and marker.read_text(encoding="utf-8").strip() == integrity:
            continue
        log(f"fetching {name}@{version} with npm pack")
        target.parent.mkdir(parents=True, exist_ok=True)
        with tempfile.TemporaryDirectory() as tmp:
            tarball = npm_pack(name, version, Path(tmp))
        found = sha512_integrity(tarball)
        if found != integrity:
            if not relock:
                raise VendorError(f"{name}@{version}: the tarball's integrity {found} is not the pinned {integrity}")
            package["integrity"] = integrity = found
        _unpack(tarball, _needed_members(lock, name), target)
        marker.write_text(integrity + "\n", encoding="utf-8")


def _model_bytes(part: dict[str, Any]) -> bytes:
    data = (package_dir(part["package"]) / part["path"]).read_bytes()
    offset = int(part.get("offset", 0))
    length = part.get("length")
    return data[offset : offset + int(length)] if length is not None else data[offset:]


def build_task(task: dict[str, Any]) -> bytes:
    """Returns the `.task` bundle of one lock entry: detector + landmark model, each with its metadata."""
    from kinect_agent.vendor.tflite_metadata import ImageInput, pack_task, with_image_metadata

    det, lm = task["detector"], task["landmarks"]
    detector = with_image_metadata(_model_bytes(det), name="pose_detector", image=ImageInput(det["mean"], det["std"]),
                                   description="BlazePose person detector (SSD, 224x224 RGB)")  # fmt: skip
    landmarks = with_image_metadata(_model_bytes(lm), name="pose_landmarks_detector",
                                    image=ImageInput(lm["mean"], lm["std"]),
                                    description="BlazePose GHUM 3D landmarks (33 points, 256x256 RGB)")  # fmt: skip
    return pack_task({"pose_detector.tflite": detector, "pose_landmarks_detector.tflite": landmarks})


def install_tasks(lock: dict[str, Any], *, relock: bool, log: Callable[[str], None]) -> None:
    """Packs every `.task` that is missing or differs from its pinned SHA-256."""
    models = FILES / "models"
    models.mkdir(parents=True, exist_ok=True)
    for task in lock["tasks"]:
        path = models / task["file"]
        if not relock and path.is_file() and hashlib.sha256(path.read_bytes()).hexdigest() == task["sha256"]:
            continue
        log(f"packing {task['file']}")
        data = build_task(task)
        found = hashlib.sha256(data).hexdigest()
        if found != task["sha256"]:
            if not relock:
                raise VendorError(
                    f"{task['file']}: the packed bundle's sha256 {found} is not the pinned {task['sha256']}"
                )
            task["sha256"] = found
        tmp = path.with_suffix(".part")
        tmp.write_bytes(data)
        os.replace(tmp, path)


def install(*, relock: bool = False, quiet: bool = False) -> None:
    """Makes files/ match lock.json; raises VendorError."""
    lock = load_lock()
    if is_installed(lock) and not relock:
        return

    def log(message: str) -> None:
        if not quiet:
            print(f"vendor: {message}", file=sys.stderr)

    FILES.mkdir(parents=True, exist_ok=True)
    install_packages(lock, relock=relock, log=log)
    install_tasks(lock, relock=relock, log=log)
    if relock:
        LOCK_PATH.write_text(json.dumps(lock, indent=2) + "\n", encoding="utf-8")
    missing = [url for url, path in all_served_files(lock).items() if not path.is_file()]
    if missing:
        raise VendorError(f"served files missing after install: {', '.join(missing)}")
    STAMP.write_text(_lock_digest() + "\n", encoding="utf-8")
    log(f"browser and pose assets ready in {FILES}")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m kinect_agent.vendor.install", description=__doc__.splitlines()[0])
    parser.add_argument("--relock", action="store_true", help="write the hashes found into lock.json")
    parser.add_argument("--quiet", action="store_true", help="print nothing when all is well")
    args = parser.parse_args(argv)
    try:
        install(relock=args.relock, quiet=args.quiet)
    except VendorError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
