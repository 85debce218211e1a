#!/usr/bin/env bash
# Every darkness-world network of the training issue, three init seeds each, as two
# lanes (one per core: two 1-thread runs train faster than one 2-thread run). Each lane
# trains its runs in order; a run resumes from its committed runs/NAME/checkpoint.pt, and
# a finished run is only re-tested (about a minute) and exported into
# hippo_probe/pretrained/ (seed 0 under the task's name, seed k as NAME_seedk). A
# readout follows its generalized network in the same lane. Start it in the background
# and leave it; `git add runs/*/checkpoint.pt` keeps the progress for the next session:
#
#   nohup bash scripts/train_networks.sh > logs/queue.log 2>&1 &
#
# A run already being trained (the same command started twice) is refused by the
# trainer's lock on its folder, so starting the queue twice does no harm. A run whose
# network is shipped and whose checkpoint was pruned (git rm) is skipped.
set -u
cd "$(dirname "$0")/.."
mkdir -p logs

train() {                       # NAME TASK SEED [extra options...]
  local name=$1 task=$2 seed=$3
  shift 3
  local shipped=${name%_s*}
  [ "$seed" = 0 ] || shipped="${shipped}_seed$seed"
  # exported only once finished: a shipped run is done, and its checkpoint may be pruned
  if [ -f "hippo_probe/pretrained/$shipped.pt" ] && [ ! -f "runs/$name/checkpoint.pt" ]; then
    echo "$(date -u +%FT%TZ) skip $name: shipped as hippo_probe/pretrained/$shipped.pt"
    return 0
  fi
  echo "$(date -u +%FT%TZ) start $name"
  local rc=0
  hippo-probe train --task "$task" --init-seed "$seed" --threads 1 --checkpoint-minutes 5 \
    --no-progress --out "runs/$name" "$@" >> "logs/$name.log" 2>&1 || rc=$?
  if [ "$rc" != 0 ]; then
    echo "$(date -u +%FT%TZ) $name failed (exit $rc): see logs/$name.log"
    return "$rc"
  fi
  # never over a shipped network (the figures were made from it): that is done by hand
  if hippo-probe export-network "runs/$name" "$shipped" --dest hippo_probe/pretrained \
      >> "logs/$name.log" 2>&1; then
    echo "$(date -u +%FT%TZ) done $name -> hippo_probe/pretrained/$shipped.pt"
  else
    echo "$(date -u +%FT%TZ) $name trained, not exported: see logs/$name.log"
  fi
}

network() {                     # TASK SEED: the study's training-set size, 40,000 steps
  train "$1_s$2" "$1" "$2" --steps 40000
}

readout() {                     # SEED: softmax readout on the frozen generalized network
  train "generalized_readout_s$1" specialized "$1" --init-from "runs/generalized_s$1" \
    --train-only classifier --steps 4000 --lr 3e-3 --lr-final 3e-4 --validate-every 100 \
    --validation-trials 300
}

# specialized_s2 sits in lane A so that the lanes end near each other: at one point
# start lane A held only localization_s2 (~6,000 steps left: the 1% rule ended seeds 0
# and 1 at 11,750), lane B ~94,000 steps
lane_a() { network generalized 0 && readout 0; network localization 0; network generalized 1 \
           && readout 1; network localization 2; network specialized 2; }
lane_b() { network specialized 0; network localization 1; network specialized 1; \
           network generalized 2 && readout 2; }

lane_a > logs/queue_a.log 2>&1 &
lane_b > logs/queue_b.log 2>&1 &
wait
