#!/usr/bin/env bash
# Algorithm 1 on the seed paper's 3x2 grid (GF goal & G !unsafe) for defender
# sizes N = 1..3 and adversary sizes M = 1..2, with the default (neighbourhood)
# observation model and with the paper's blind correct/wrong model, under the
# default removal, --paper-literal and --prune-adversary; as a control, also
# with exact observations (p_obs = 1), and with exact observations and moves
# that always succeed (p_NA = p_A = 1).
# Writes results/pruning/<model>/<variant>/N<N>-M<M>/ and results/pruning/table.md.
set -euo pipefail
cd "$(dirname "$0")/../.."
cargo build --quiet
bin=target/debug/posg-fsc
games=experiments/pruning/games
mkdir -p "$games"
rustc --edition 2024 -O experiments/pruning/make_grids.rs -o target/debug/make_grids \
  --extern posg_fsc=target/debug/libposg_fsc.rlib -L dependency=target/debug/deps
target/debug/make_grids "$games"
formula='GF goal & G !unsafe'
out=results/pruning
rm -rf "$out"
for model in neighbourhood blind exact exact-sure; do
  game="$games/grid-3x2.posg.json"
  [ "$model" = blind ] && game="$games/grid-3x2-blind.posg.json"
  [ "$model" = exact ] && game="$games/grid-3x2-exact.posg.json"
  [ "$model" = exact-sure ] && game="$games/grid-3x2-exact-sure.posg.json"
  for variant in default paper-literal prune-adversary; do
    flags=()
    [ "$variant" = paper-literal ] && flags=(--paper-literal)
    [ "$variant" = prune-adversary ] && flags=(--prune-adversary)
    for n in 1 2 3; do
      for m in 1 2; do
        dir="$out/$model/$variant/N$n-M$m"
        mkdir -p "$dir"
        "$bin" prune "$game" --ltl "$formula" --def-nodes "$n" --adv-nodes "$m" \
          ${flags[@]+"${flags[@]}"} --out "$dir" > "$dir/stdout.txt"
      done
    done
  done
done
python3 experiments/pruning/summarise.py "$out" > "$out/table.md"
