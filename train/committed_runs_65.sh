#!/usr/bin/env bash
# Issue 65: SAC and recurrent PPO beside PPO (and MAPPO on vee5) on the headline tasks. The exact commands of the 18
# trainings (2 algorithms x close_formation, vee5, reconfiguration x training seeds 0, 1, 2; set-point actions; each
# task's benchmark configuration; hyperparameters and step counts in train/hyperparams/sac.yml and
# recurrent_ppo.yml), run two at a time on the 2-core machine (one core each: NUMBA_NUM_THREADS=1, torch on 1
# thread), then published into train/policies/ with their curves and validation history, then evaluated exactly as
# the committed PPO policies: 100 held-out test episodes per turbulence level (sigma 0, 1, 1.5; close_formation also
# 0.5, its protocol's), the three new seeds beside the three committed PPO seeds and the classical baselines in one
# command per task (the same episodes: every comparison is paired; two tasks at a time), recorded with
# `formation-env publish levels`, and compared with PPO paired by episode on the task's headline metric
# (`formation-env publish versus`).
#
# Run directories: RUNS/<task>_<algo>_seed<k> (log: RUNS/<task>_<algo>_seed<k>.log); published policies:
# train/policies/<task>_<algo>_setpoints_seed<k>.{zip,json} with _curve.csv and _evaluations.json; evaluations:
# RUNS/eval/<task> (log: RUNS/eval/<task>.log); records: train/policies/<task>_algorithms_levels.json (SAC, recurrent
# PPO, PPO and the baselines) and train/policies/<task>_<algo>_setpoints_versus_ppo.json.
#
# Usage: bash train/committed_runs_65.sh [RUNS_DIR]
#   ONLY="algo:task:seed ..."  train and publish a subset (e.g. ONLY="sac:vee5:1" to redo one run)
#   NO_PUBLISH=1               train only;  NO_EVAL=1  train and publish, do not evaluate
#   PRINT=1                    print the training commands and exit
set -euo pipefail
cd "$(dirname "$0")/.."
RUNS=${1:-runs/committed65}
FE=${FE:-.venv/bin/formation-env}
PY=${PY:-.venv/bin/python}

# algo task steps seed: the steps are the files' n_timesteps (a test holds them equal), repeated here so that each
# command is complete; each run ~25 min with a core to itself (the files' comments: the measured throughput)
jobs_list() {
  for seed in 0 1 2; do
    echo "sac close_formation 700000 $seed"
    echo "sac vee5 575000 $seed"
    echo "sac reconfiguration 700000 $seed"
    echo "recurrent_ppo close_formation 1500000 $seed"
    echo "recurrent_ppo vee5 700000 $seed"
    echo "recurrent_ppo reconfiguration 1000000 $seed"
  done
}
selected() {
  if [ -z "${ONLY:-}" ]; then cat; return; fi
  while read -r algo task steps seed; do
    case " $ONLY " in *" $algo:$task:$seed "*) echo "$algo $task $steps $seed" ;; esac
  done
}
command_of() {  # the training command of one run
  local algo=$1 task=$2 steps=$3 seed=$4
  echo "NUMBA_NUM_THREADS=1 $FE train --scenario $task --algo $algo --action-mode setpoints --steps $steps --seed $seed" \
       "--out $RUNS/${task}_${algo}_seed${seed} --no-progress-bar"
}
run_one() {
  local algo=$1 task=$2 steps=$3 seed=$4
  local out="$RUNS/${task}_${algo}_seed${seed}"
  NUMBA_NUM_THREADS=1 "$FE" train --scenario "$task" --algo "$algo" --action-mode setpoints --steps "$steps" \
    --seed "$seed" --out "$out" --no-progress-bar > "$out.log" 2>&1
}
export -f run_one
export RUNS FE

if [ -n "${PRINT:-}" ]; then
  jobs_list | selected | while read -r a t s k; do command_of "$a" "$t" "$s" "$k"; done
  exit 0
fi
mkdir -p "$RUNS"
jobs_list | selected | xargs -P 2 -L 1 bash -c 'run_one "$0" "$1" "$2" "$3"'
[ -n "${NO_PUBLISH:-}" ] && exit 0

jobs_list | selected | while read -r algo task _ seed; do  # ONLY: publish the runs it trained
  run="$RUNS/${task}_${algo}_seed${seed}"
  wall=$("$PY" -c "import json,sys; print(json.load(open(sys.argv[1]))['wall_s'])" "$run/summary.json" < /dev/null)
  # close_formation's policies fly through the guard's lateral clip, as its PPO policies (docs/close_formation.md)
  extra=()
  if [ "$task" = close_formation ]; then extra=(--guard '{"clip_ramp": 0.25}'); fi
  if [ ! -f "$run/best_model.zip" ]; then  # every validation had a collision: the selection rule chose no model
    extra+=(--model final --note "every validation of the run had a collision: the final model")
  fi
  "$FE" publish run "$run" "${task}_${algo}_setpoints_seed${seed}" --wall-s "$wall" ${extra[@]+"${extra[@]}"} \
    < /dev/null
done
[ -n "${NO_EVAL:-}" ] && exit 0

P=train/policies
levels_of() {  # the task's protocol levels, with sigma 1.5 for every task
  case $1 in close_formation) echo "0 0.5 1 1.5" ;; *) echo "0 1 1.5" ;; esac
}
baselines_of() {  # the classical baselines of the task's PPO record, and the station keeper everywhere
  case $1 in vee5) echo "--policy pid --policy station_keeper" ;;
             *) echo "--policy pid --policy pid_formation --policy station_keeper" ;; esac
}
eval_one() {  # one evaluation per task: SAC, recurrent PPO and PPO (3 seeds each) and the baselines, same episodes
  local task=$1 dir="$RUNS/eval/$1" args="--scenario $1"
  for group in sac recurrent_ppo ppo; do
    for k in 0 1 2; do args+=" --policy $P/${task}_${group}_setpoints_seed$k.zip"; done
  done
  args+=" $(baselines_of "$task") --turbulence $(levels_of "$task") --episodes 100 --benefit --no-plots"
  # shellcheck disable=SC2086  # $args is a list of plain words
  NUMBA_NUM_THREADS=1 "$FE" evaluate $args --out "$dir" > "$dir.log" 2>&1
  "$FE" publish levels "$dir" "$P/${task}_algorithms_levels.json" \
    --command "formation-env evaluate $args --out DIR"
}
export -f eval_one levels_of baselines_of
export P PY FE
mkdir -p "$RUNS/eval"
printf '%s\n' close_formation vee5 reconfiguration | xargs -P 2 -L 1 bash -c 'eval_one "$0"'
for task in close_formation vee5 reconfiguration; do
  for algo in sac recurrent_ppo; do
    "$FE" publish versus "$P/${task}_algorithms_levels.json" "${task}_${algo}_setpoints" "${task}_ppo_setpoints" \
      "$P/${task}_${algo}_setpoints_versus_ppo.json"
  done
done
