#!/usr/bin/env bash
# Algorithm 1 on the seed paper's 3x2 grid (GF goal & G !unsafe) for defender
# sizes N = 1..3 and adversary sizes M = 1..2, with the default (neighbourhood)
# observation model and with the paper's blind correct/wrong model, under the
# default removal, --paper-literal and --prune-adversary; as controls, also
# with exact observations (p_obs = 1), and with exact observations and moves
# that always succeed (p_NA = p_A = 1).
# Writes experiments/pruning/games/, results/pruning/<model>/<variant>/N<N>-M<M>/
# and results/pruning/table.md.
set -euo pipefail
cd "$(dirname "$0")/../.."
cargo build --quiet
bin=target/debug/posg-fsc
games=experiments/pruning/games
mkdir -p "$games"
"$bin" example grid --out "$games/neighbourhood.posg.json"
"$bin" example grid --observation blind --out "$games/blind.posg.json"
"$bin" example grid --p-obs-defender 1 --p-obs-adversary 1 --out "$games/exact.posg.json"
"$bin" example grid --p-obs-defender 1 --p-obs-adversary 1 --p-na 1 --p-a 1 \
  --out "$games/exact-sure.posg.json"
formula='GF goal & G !unsafe'
out=results/pruning
rm -rf "$out"
for model in neighbourhood blind exact exact-sure; do
  for variant in default paper-literal prune-adversary; do
    flags=()
    [ "$variant" = paper-literal ] && flags=(--paper-literal)
    [ "$variant" = prune-adversary ] && flags=(--prune-adversary)
    for n in 1 2 3; do
      for m in 1 2; do
        dir="$out/$model/$variant/N$n-M$m"
        mkdir -p "$dir"
        "$bin" prune "$games/$model.posg.json" --ltl "$formula" --def-nodes "$n" --adv-nodes "$m" \
          ${flags[@]+"${flags[@]}"} --out "$dir" > "$dir/stdout.txt"
      done
    done
  done
done
python3 experiments/pruning/summarise.py "$out" > "$out/table.md"
