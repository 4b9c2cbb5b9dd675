"""PAYNT 0.5.0's POSMG synthesis with K memory nodes on every observation.

    python paynt_full_memory.py DIR --memory K [--timeout S]

PAYNT gives an observation seen in a single player-0 state one memory node
(`set_imperfect_memory_size` in `paynt/quotient/posmg.py`): there the
memory falls back to 0. This script replaces that method on the loaded
quotient by one that gives every player-0 observation K nodes, and runs
PAYNT's own synthesiser on `DIR/sketch.templ` with `DIR/sketch.props`, so
that its optimum is over the family docs/formats.md section 6 compares
posg-fsc with. Needs the `paynt==0.5.0` and `stormpy==2.0.0` wheels; prints
PAYNT's log and its optimum (for a `Pmin` query, the opponent's
probability).
"""
import argparse
import logging
import os


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("directory", help="a model of PAYNT's models/posmg/")
    parser.add_argument("--memory", type=int, required=True, help="memory nodes K")
    parser.add_argument("--timeout", type=float, default=300.0, help="seconds")
    args = parser.parse_args()
    logging.basicConfig(level=logging.INFO, format="%(message)s")
    import paynt.parser.sketch
    import paynt.pomdp.posmg.synthesizer
    import paynt.utils.timer

    paynt.utils.timer.GlobalTimer.start(args.timeout)
    quotient, task = paynt.parser.sketch.Sketch.load_sketch(
        os.path.join(args.directory, "sketch.templ"),
        os.path.join(args.directory, "sketch.props"),
        precision=1e-4, task_kwargs={"memory_size": args.memory})

    def every_observation(memory):
        quotient.opt_player_observation_memory_size = {
            o: memory for o in quotient.opt_player_observations}
        quotient.set_manager_memory_vector()
        return quotient._unfold_memory()

    quotient.set_imperfect_memory_size = every_observation
    result = paynt.pomdp.posmg.synthesizer.PosmgSynthesizer(quotient, task).run()
    print("optimum", result.value)


if __name__ == "__main__":
    main()
