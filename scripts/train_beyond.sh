#!/usr/bin/env bash
# The runs that go beyond the shipped networks, as two lanes (one per core: two 1-thread
# runs train faster than one 2-thread run). Each run resumes from runs/NAME/checkpoint.pt;
# a run already being trained is refused by the trainer's lock on its folder, so starting
# this twice does no harm. Start it in the background and leave it:
#
#   nohup bash scripts/train_beyond.sh > logs/beyond.log 2>&1 &
#
# lane A  generalized_s0_continued: the shipped generalized network (seed 0) trained on
#         with a fresh schedule (3e-4 -> 3e-5) for up to 60,000 more steps, the 1% rule
#         checked from 15,000; snapshots every 2,500 steps for the arena probe against step
#         (python analyses/arena_readout.py --networks runs/generalized_s0_continued/
#          snapshots/step_*.pt --sizes 2000 --tau-size 2000
#          --out analyses/data/arena_probe_steps)
# lane B  the map-ingredient variants on the generalized task, one seed, 20,000 steps each,
#         each a labelled departure from the study (hippo_probe.model.variants)
set -u
cd "$(dirname "$0")/.."
mkdir -p logs

train() {                       # NAME [options...]
  local name=$1
  shift
  echo "$(date -u +%FT%TZ) start $name"
  hippo-probe train --threads 1 --checkpoint-minutes 5 --no-progress --out "runs/$name" \
    "$@" >> "logs/$name.log" 2>&1 || { echo "$(date -u +%FT%TZ) $name failed"; return 1; }
  echo "$(date -u +%FT%TZ) done $name"
}

lane_a() {
  train generalized_s0_continued --task generalized --init-from generalized --init-seed 0 \
    --steps 60000 --lr 3e-4 --lr-final 3e-5 --snapshot-every 2500
}
lane_b() {
  train generalized_placecells_s0 --task generalized --variant placecells --init-seed 0 \
    --steps 20000 --snapshot-every 5000
}

lane_a > logs/beyond_a.log 2>&1 &
lane_b > logs/beyond_b.log 2>&1 &
wait
