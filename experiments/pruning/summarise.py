"""Tabulates the structures.json files written by run.sh (Markdown on stdout)."""
import json
import sys
from pathlib import Path

root = Path(sys.argv[1])
print("| observation | variant | N | M | GMC states | SCCs | attempts | stopped | kept | values of the kept structures | stops (SCC, pair: player block) |")
print("|---|---|---|---|---|---|---|---|---|---|---|")
for model in ["neighbourhood", "blind", "exact", "exact-sure"]:
    for variant in ["default", "paper-literal", "prune-adversary"]:
        for n in [1, 2, 3]:
            for m in [1, 2]:
                s = json.loads((root / model / variant / f"N{n}-M{m}" / "structures.json").read_text())
                values = ", ".join(f"{x['value']:.6g}" for x in s["structures"]) or "-"
                stops = "; ".join(
                    f"{t['scc']},{t['pair']}: {t['player']} (g{t['node']}, {t['observation']}) keeps {t['last_entry']['action']}"
                    for t in s["stops"]
                ) or "-"
                stopped = sum(a["stopped"] for a in s["attempts"])
                print(f"| {model} | {variant} | {n} | {m} | {s['gmc_states']} | {s['sccs']} | {len(s['attempts'])} | {stopped} | {len(s['structures'])} | {values} | {stops} |")
