#!/usr/bin/env bash
# Packaging check: build the wheel, install it (not editable) into a fresh venv and use it as a user would.
#   1. core only: `rdmp-gym --help` and `rdmp-gym fit` work; `rdmp-gym train` names the extra it needs.
#   2. with the `agents` extra (torch pinned to the CPU build by .ci/constraints-cpu.txt): `--help`,
#      `--version`, a one-update `train` on the wiping env, and `gym.make` finding the packaged XML.
# Everything runs from a temporary directory, so the repository's folders cannot stand in for the wheel.
set -euo pipefail
ROOT="$(cd "$(dirname "$0")/.." && pwd)"
PYTHON="${PYTHON:-python3}"
WORK="$(mktemp -d)"
trap 'rm -rf "$WORK"' EXIT
export MUJOCO_GL="${MUJOCO_GL:-egl}" OMP_NUM_THREADS=1 PIP_DISABLE_PIP_VERSION_CHECK=1
step() { printf '[wheel-check %3ss] %s\n' "$SECONDS" "$*"; }

step "build the wheel"
"$PYTHON" -m pip wheel --quiet --no-deps --wheel-dir "$WORK/dist" "$ROOT" 2>&1 | grep -v "Location '" || true
WHEEL="$(ls "$WORK"/dist/rdmp_gym-*.whl)"
rm -rf "$ROOT/build"
for member in rdmp_gym/agents/learners/__init__.py rdmp_gym/envs/robots/armar3/legacy_scene.xml \
              rdmp_gym-*.dist-info/licenses/LICENSE; do
  "$PYTHON" - "$WHEEL" "$member" <<'PY'
import fnmatch, sys, zipfile
names = zipfile.ZipFile(sys.argv[1]).namelist()
sys.exit(0 if fnmatch.filter(names, sys.argv[2]) else f"wheel lacks {sys.argv[2]}")
PY
done

step "fresh venv, core install"
"$PYTHON" -m venv "$WORK/venv"
BIN="$WORK/venv/bin"
"$BIN/pip" install --quiet --no-compile "$WHEEL" 2>&1 | grep -v "Location '" || true
cd "$WORK"
"$BIN/rdmp-gym" --help >/dev/null
"$BIN/python" -c "import sys, rdmp_gym; assert not {'gymnasium', 'mujoco', 'matplotlib'} & set(sys.modules)"
"$BIN/rdmp-gym" fit --style 1 --n-periodic 20 --n-transient 20 --out "$WORK/fit"
test -s "$WORK/fit/dmp.json"
if "$BIN/rdmp-gym" train --out "$WORK/core-train" 2>"$WORK/err.txt"; then
  echo "train without the agents extra should fail" >&2; exit 1
fi
grep -q 'rdmp-gym\[agents\]' "$WORK/err.txt" || { cat "$WORK/err.txt" >&2; exit 1; }

step "same venv, agents extra (CPU torch)"
"$BIN/pip" install --quiet --no-compile -c "$ROOT/.ci/constraints-cpu.txt" "$WHEEL[agents]" 2>&1 \
  | grep -v "Location '" || true
"$BIN/rdmp-gym" --help >/dev/null
"$BIN/rdmp-gym" --version
"$BIN/python" - <<'PY'
import gymnasium as gym
import torch

import rdmp_gym.envs  # registers the env ids

assert "+cpu" in torch.__version__ or not torch.cuda.is_available(), torch.__version__
assert "site-packages" in rdmp_gym.__file__, rdmp_gym.__file__
env = gym.make("rdmp_gym/ArmarWipe-v1", n_periodic=10, n_transient=10)
env.reset(seed=0)
xml = env.unwrapped.scene.xml_file
assert "site-packages" in str(xml) and xml.is_file(), xml
print("gym.make found", xml)
PY
"$BIN/rdmp-gym" train --agent pi2 --updates 1 --rollouts 2 --workers 1 --env-option n_periodic 10 n_transient 10 \
  --out "$WORK/train"
test -s "$WORK/train/dmp.json"
step "ok"
