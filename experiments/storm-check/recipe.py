"""The value of phi on a chain written by `posg-fsc export-gmc`, checked by
Storm (the recipe of docs/guide.md; run.py calls it for every case).

Usage: python3 recipe.py DIR/chain.drn 'G F "goal" & G !"unsafe"'
"""
import sys

import stormpy
import stormpy.developer


def storm_value(drn_file, formula):
    """P=? [ X phi ] in state 0 (the fresh initial state), with Storm in
    sound mode and Eigen's sparse LU as the linear equation solver."""
    model = stormpy.build_model_from_drn(drn_file)
    prop = stormpy.parse_properties(f"P=? [ X ({formula}) ]")[0]
    env = stormpy.Environment()
    env.solver().force_soundness = True  # with Eigen: SparseLU, exact up to rounding
    env.solver().set_linear_equation_solver_type(stormpy.developer.EquationSolverType.EIGEN)
    result = stormpy.model_checking(model, prop, environment=env)
    return result.get_value(model.initial_states[0])


if __name__ == "__main__":
    print(storm_value(sys.argv[1], sys.argv[2]))
