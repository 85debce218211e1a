#!/usr/bin/env bash
# One entry point for the README's quick start.
#   bash quickstart.sh main   set everything up, then run the main job
#   bash quickstart.sh test   set everything up, then run the tests
# Set-up is idempotent: a virtualenv in .venv, torch 2.13.0 (CPU) first, then the project.
set -euo pipefail
cd "$(dirname "$0")"
what="${1:-main}"
case "$what" in main|test) ;; *) echo "usage: bash quickstart.sh {main|test}" >&2; exit 2 ;; esac

PY="${PYTHON:-python3}"
if [ ! -x .venv/bin/python ]; then
  "$PY" -m venv .venv
fi
. .venv/bin/activate
export PIP_DISABLE_PIP_VERSION_CHECK=1
# Install torch 2.13.0 before the project, so the project's range is already met. Where
# the default index serves a CUDA build (PyPI on Linux x86_64 does: several GB), set
# TORCH_INDEX_URL=https://download.pytorch.org/whl/cpu to take the CPU build instead.
python -c "import torch, sys; sys.exit(0 if torch.__version__.startswith('2.13.0') else 1)" \
  2>/dev/null || pip install -q "torch==2.13.0" ${TORCH_INDEX_URL:+--index-url "$TORCH_INDEX_URL"}
pip install -q -e ".[model,test,nwb,distributed]"
export MPLBACKEND=Agg

if [ "$what" = test ]; then
  set +e
  python -m pytest -q "${@:2}"
  rc=$?
  # pytest exits 5 when it collected no tests: that must fail, not pass silently.
  if [ "$rc" -eq 5 ]; then echo "pytest collected no tests" >&2; exit 1; fi
  exit "$rc"
else
  # the main job refreshes this clone's tracked copies (paper_figures/), so `git diff`
  # shows what this machine reproduced
  hippo-probe main --refresh-tracked . "${@:2}"
fi
