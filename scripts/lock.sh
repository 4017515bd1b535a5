#!/usr/bin/env bash
# Regenerates requirements/*.lock: every dependency, transitive ones too, pinned with the hashes of all its published
# files, for every platform (the agent runs on Windows too). Run after changing a pin. The two deployables' locks come
# from their own pyproject.toml (packages/agent, packages/server), and so do the locks of the tools each side's tests
# need in its environment beside them (their `tests` dependency group, pinned within the side's lock); the development
# and test locks from the root's.
set -euo pipefail
source "$(dirname "$0")/_venv.sh" test  # uv: in the test extra
cd "$ROOT"
compile() { uv pip compile "$@" --generate-hashes --universal --python-version 3.11 --quiet; }
compile packages/agent/pyproject.toml -o requirements/agent.lock
compile packages/server/pyproject.toml -o requirements/server.lock
for side in agent server; do
  compile --group "packages/$side/pyproject.toml:tests" -c "requirements/$side.lock" -o "requirements/$side-tests.lock"
done
for extra in dev test; do
  compile pyproject.toml --extra "$extra" -o "requirements/$extra.lock"
done
printf 'mediapipe==1.2.3\nflatbuffers==25.12.19\nnumpy==2.4.6\n' | compile - --no-deps \
  -o requirements/vendor.lock  # the Dockerfile's pose-asset stage
echo "requirements/{agent,server,agent-tests,server-tests,dev,test,vendor}.lock regenerated" >&2
