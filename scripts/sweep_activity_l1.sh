#!/usr/bin/env bash
# The L1 activity cost of the `nonneg` variant, chosen by a short sweep: one run per
# weight on the generalized task (darkness world, init seed 0), 4,000 steps each with the
# stopping rule off so every point has the same budget; the weight kept is the largest
# whose validation error is within 10% of the unpenalised run's (weight 0). Summarised by
#
#   python analyses/activity_l1_sweep.py runs/sweep_nonneg_l1_*
#
# Then the study's network trained the same way (runs/sweep_faithful): the sweep's
# reference, which separates what non-negative units do from what their activity cost
# does (docs/guides/results.md, "Non-negative units or their activity cost?").
#
# One lane (one core); start it in the background and leave it:
#
#   nohup bash scripts/sweep_activity_l1.sh > logs/sweep_l1.log 2>&1 &
set -u
cd "$(dirname "$0")/.."
# the project's virtual environment, where it has one: a job started from a shell that
# did not activate it still finds the command line
if [ -x .venv/bin/hippo-probe ]; then PATH="$PWD/.venv/bin:$PATH"; fi
mkdir -p logs
for weight in 0 0.01 0.1 1; do
  name=sweep_nonneg_l1_$weight
  if [ -f "runs/$name/log.json" ] && grep -q '"test"' "runs/$name/log.json"; then
    echo "$(date -u +%FT%TZ) $name finished before; kept"     # its network and log are committed
    continue
  fi
  echo "$(date -u +%FT%TZ) start $name"
  hippo-probe train --threads 1 --checkpoint-minutes 5 --no-progress --out "runs/$name" \
    --task generalized --variant nonneg --activity-l1 "$weight" --init-seed 0 \
    --steps 4000 --stop-improvement 0 >> "logs/$name.log" 2>&1 \
    || { echo "$(date -u +%FT%TZ) $name failed"; exit 1; }
  echo "$(date -u +%FT%TZ) done $name"
done
train_reference() {
  local name=sweep_faithful
  if [ -f "runs/$name/log.json" ] && grep -q '"test"' "runs/$name/log.json"; then
    echo "$(date -u +%FT%TZ) $name finished before; kept"
    return 0
  fi
  echo "$(date -u +%FT%TZ) start $name"
  hippo-probe train --threads 1 --checkpoint-minutes 5 --no-progress --out "runs/$name" \
    --task generalized --init-seed 0 --steps 4000 --stop-improvement 0 \
    >> "logs/$name.log" 2>&1 || { echo "$(date -u +%FT%TZ) $name failed"; return 1; }
  echo "$(date -u +%FT%TZ) done $name"
}
train_reference
