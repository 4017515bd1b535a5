#!/usr/bin/env bash
# Regenerates requirements/*.lock from pyproject.toml: every dependency, transitive ones too, pinned with the hashes of
# all its published files, for every platform (the agent runs on Windows too). Run after changing a pin.
set -euo pipefail
source "$(dirname "$0")/_venv.sh" test
cd "$ROOT"
python -m pip install --quiet "uv==0.13.9"
for extra in agent server dev test; do
  uv pip compile pyproject.toml --extra "$extra" --generate-hashes --universal --python-version 3.11 \
    -o "requirements/$extra.lock" --quiet
done
printf 'mediapipe==1.2.3\nflatbuffers==25.12.19\nnumpy==2.4.6\n' | uv pip compile - --no-deps --generate-hashes \
  --universal --python-version 3.11 -o requirements/vendor.lock --quiet  # the Dockerfile's pose-asset stage
echo "requirements/{agent,server,dev,test,vendor}.lock regenerated" >&2
