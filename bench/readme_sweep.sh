#!/usr/bin/env bash
# The sweep behind the report figure and tables of docs/how-to/reproduce-paper.md: goal-split (no LLM) and expert
# subgoals, tasks 1, 6, 11, 16 of the five domains, first plan of LAMA with a 30 s search
# limit (the paper: anytime LAMA, 1000 s). SA is solved once (N = 1); MA and TwoStep for
# N = 2..4; expert subgoals exist for N = 2 only. One MLflow experiment for all three.
set -euo pipefail
cd "$(dirname "$0")/.."
EXP=${EXP:-readme-goal-split}
COMMON=(planner=lama-first planner.time_limit_s=30 "mlflow.experiment=$EXP"
        hydra/launcher=joblib hydra.launcher.n_jobs=2 task=1,6,11,16)
.venv/bin/twostep -m method=sa agents=1 domain=barman,blocksworld,grippers,termes,tyreworld "${COMMON[@]}"
.venv/bin/twostep -m method=ma,twostep decomposer=goal-split agents=2,3,4 \
    domain=barman,blocksworld,grippers,termes,tyreworld "${COMMON[@]}"
.venv/bin/twostep -m method=twostep decomposer=expert agents=2 \
    domain=blocksworld,grippers,termes,tyreworld "${COMMON[@]}"
.venv/bin/twostep-report --experiment "$EXP" --out docs/report
