"""posg_fsc: finite-state controllers for partially observable stochastic
games (POSGs) under LTL objectives: exact values, adjoint gradients, max-min
optimisation against a worst-case adversary, and certified bounds.

A thin binding of the Rust library of the same name; the command line
`posg-fsc` computes the same numbers. File formats: docs/formats.md; the
method: docs/method.md.
"""

from os import PathLike
from typing import Any, Callable, Literal, Optional, Sequence, Union

import numpy as np
import numpy.typing as npt

__version__: str

Role = Literal["defender", "adversary"]
Path = Union[str, "PathLike[str]"]
ControllerLike = Union["Controller", str, "PathLike[str]"]
"""A Controller of the game, a controller file's path, or "uniform:K"."""
Props = Union[str, "PathLike[str]"]
"""A query of a Storm/PRISM property file ('Pmax=? [F "goal"]', recognised by
its "=?"), or the path of such a file (docs/formats.md section 6). Every
function takes `props=` instead of `ltl=`; `Pmin=? [PATH]` makes the
complement of PATH the objective. An expected-reward query
('R{"steps"}min=? [F "goal"]', docs/method.md section 9) is taken by
Game.evaluate, certify and solve, so far."""

class Error(Exception):
    """Base class of every error posg_fsc raises; the message is the one the
    command line prints."""

class GameFormatError(Error):
    """A game or controller that is malformed (the message names the file and
    the JSON path or line) or does not fit the game."""

class FormulaError(Error):
    """An LTL formula that cannot be parsed (the message names the position)
    or translated, or an automaton that cannot be read."""

class NumericalError(Error):
    """A linear system that cannot be solved to its tolerance, or certified
    bounds that contradict each other: the number is not trusted."""

class SettingsError(Error, ValueError):
    """A setting, size or other argument out of range (also a ValueError)."""

class Game:
    """A partially observable stochastic game: states labelled with atomic
    propositions, a defender and an adversary with their actions and
    observations, and the transition probabilities. Immutable."""

    @staticmethod
    def load(path: Path) -> Game:
        """Reads and validates a game file: JSON (docs/formats.md section 1)
        or the binary form *.posg.bin (section 11). Raises GameFormatError
        naming the file and the JSON path of the first problem."""
    @staticmethod
    def from_json(text: str, name: str = "<string>") -> Game:
        """Parses a game from JSON text; `name` stands for the file in
        error messages."""
    @staticmethod
    def from_drn(path: Path) -> Game:
        """Imports a model from Storm's DRN format (docs/formats.md section
        6): a POMDP, MDP or DTMC as a game without adversary, an SMG or
        POSMG (PAYNT's games) as a turn-based game with one, with its
        rewards; action labels renamed because they are not names (SAYNT's
        `(init)` is `_init_`) are reported as a warning."""
    @staticmethod
    def from_arrays(
        transitions: Any,
        initial: Any = 0,
        *,
        observations: Any = None,
        labels: Optional[dict[str, Any]] = None,
        rewards: Optional[dict[str, Any]] = None,
        states: Optional[Sequence[str]] = None,
        actions: Optional[Sequence[str]] = None,
        observation_names: Optional[Sequence[str]] = None,
        adversary_observations: Any = None,
        adversary_actions: Optional[Sequence[str]] = None,
        adversary_observation_names: Optional[Sequence[str]] = None,
        name: Optional[str] = None,
    ) -> Game:
        """A game from numpy arrays: transitions[s, a, s'] (a POMDP or MDP)
        or transitions[s, a, b, s'] (a game), rows summing to 1 (all zero:
        the action is left out of the state); initial a state index or a
        distribution; observations per state an index or a (states,
        observations) array of probabilities (default: the state is seen);
        labels {proposition: state indices or a boolean array}; rewards
        {name: (states,) state rewards or action rewards shaped like
        transitions without its last axis}. Names default to s0, a0, o0,
        b0, ... A problem is a SettingsError naming the array and index."""
    @staticmethod
    def from_stormpy(model: Any) -> Game:
        """A game from a model built by stormpy (a sparse POMDP, MDP, DTMC,
        SMG or POSMG, as stormpy.build_model or PAYNT return it), with its
        choice labels, observations and reward models, by way of Storm's
        DRN export; errors name it `stormpy model`. Needs stormpy."""
    def to_json(self) -> str:
        """The game as JSON text, which Game.from_json reads back."""
    def save(self, path: Path, binary: bool = False) -> None:
        """Writes the game: JSON, or the binary form with binary=True."""
    @property
    def name(self) -> Optional[str]:
        """The game's name, if it has one."""
    @property
    def states(self) -> list[str]:
        """The state names, in index order."""
    @property
    def num_states(self) -> int:
        """The number of states."""
    @property
    def propositions(self) -> list[str]:
        """The atomic propositions that label some state."""
    @property
    def labels(self) -> list[tuple[str, list[str]]]:
        """For each state (by name), the propositions that hold in it."""
    @property
    def initial(self) -> list[tuple[str, float]]:
        """The initial distribution as (state name, probability) pairs."""
    @property
    def has_adversary(self) -> bool:
        """Whether the game has an adversary (False for a POMDP)."""
    @property
    def defender_actions(self) -> list[str]:
        """The defender's actions (axis 3 of a defender's probabilities)."""
    @property
    def defender_observations(self) -> list[str]:
        """The defender's observations (axis 1 of a defender's probabilities)."""
    @property
    def adversary_actions(self) -> list[str]:
        """The adversary's actions."""
    @property
    def adversary_observations(self) -> list[str]:
        """The adversary's observations."""
    def evaluate(
        self,
        ltl: Optional[str] = None,
        defender: Optional[ControllerLike] = None,
        adversary: Optional[ControllerLike] = None,
        gradient: bool = False,
        solver: Literal["auto", "lu", "krylov"] = "auto",
        tolerance: Optional[float] = None,
        lu_limit: Optional[int] = None,
        allow_unused_propositions: bool = False,
        props: Optional[Props] = None,
    ) -> Evaluation:
        """The exact value P(trace |= ltl) of a controller pair (default
        "uniform:1" for both), as `posg-fsc eval`; with gradient=True also
        dV/d mu of both players (docs/method.md sections 1-2). `solver`,
        `tolerance` and `lu_limit` are the command line's --solver,
        --tolerance and --lu-limit. With `props=` instead of `ltl=`, the
        query is restated in its own terms in `query`; an expected-reward
        query gives the expected total reward until its target (inf where
        the target is missed with positive probability; docs/method.md
        section 9)."""

class Controller:
    """A finite-state controller of one player: in node g, on observation o,
    it moves to node g' and plays action u with probability mu(g', u | g, o),
    starting from the `initial` node distribution. Belongs to its game.

    `probabilities` has axes (node, observation, next_node, action):
    probabilities[g, o, g2, u] = mu(g2, u | g, o); each probabilities[g, o]
    sums to 1; zero entries are outside the support."""

    @staticmethod
    def load(path: Path, game: Game) -> Controller:
        """Reads a controller file (*.fsc.json, docs/formats.md section 2)
        for `game`; the player is the file's `player` field."""
    @staticmethod
    def from_json(text: str, game: Game, role: Role, name: str = "<string>") -> Controller:
        """Parses a controller of `role` in `game` from JSON text."""
    @staticmethod
    def uniform(game: Game, role: Role, nodes: int) -> Controller:
        """`nodes` nodes, starting in node 0, uniform over all (next node,
        enabled action) pairs in every block (the command line's uniform:K)."""
    @staticmethod
    def from_probabilities(
        game: Game,
        role: Role,
        probabilities: npt.ArrayLike,
        initial: Optional[npt.ArrayLike] = None,
    ) -> Controller:
        """The controller with these probabilities (axes (node, observation,
        next_node, action)) and initial distribution (default: node 0).
        Each probabilities[g, o] and the initial distribution must sum to 1
        within 1e-6 (the tolerance of docs/formats.md section 1) and are
        then rescaled to sum to 1 exactly; a row further off raises
        GameFormatError naming the node, the observation (its index) and
        the sum."""
    def to_json(self) -> str:
        """The controller file's JSON text."""
    def save(self, path: Path) -> None:
        """Writes the controller file (*.fsc.json)."""
    @property
    def role(self) -> Role:
        """"defender" or "adversary"."""
    @property
    def nodes(self) -> int:
        """The number of nodes."""
    @property
    def observations(self) -> list[str]:
        """The player's observations (axis 1 of probabilities)."""
    @property
    def actions(self) -> list[str]:
        """The player's actions (axis 3 of probabilities)."""
    @property
    def probabilities(self) -> npt.NDArray[np.float64]:
        """mu as an array with axes (node, observation, next_node, action)."""
    @property
    def initial(self) -> npt.NDArray[np.float64]:
        """The initial node distribution, shape (nodes,)."""
    @property
    def support_size(self) -> int:
        """The number of supported entries (g, o, g', u)."""

class Query:
    """A property file's query restated in its own terms (eval's `query`)."""

    text: str
    """The query as written."""
    value: float
    """Its value: for Pmin=? [PATH], 1 - the value of the complement of
    PATH; for a reward query the expected reward (inf where the target is
    missed with positive probability)."""
    error_bound: float
    """A bound on |value - exact value| (docs/method.md section 8)."""
    certified: Optional[list[float]]
    """For a solved query, [lo, hi] in its own terms: for Pmax, lo is what
    the returned defender guarantees and hi bounds every defender; for Pmin
    (the probability kept low), hi is the guarantee and lo the bound."""
    target_probability: Optional[float]
    """For a reward query, the probability of reaching its target."""

class Evaluation:
    """The value of a controller pair, with the names of `posg-fsc eval`'s
    report."""

    value: float
    """V = P(trace |= phi), or an expected reward (inf where the target is
    missed with positive probability)."""
    query: Optional[Query]
    """With props=, the query restated in its own terms."""
    error_bound: float
    """A bound on |value - exact value| (docs/method.md section 8)."""
    residual: float
    """max |(I - Q) x - b| of the linear solve."""
    gmc_states: int
    """States of the global Markov chain explored."""
    gmc_transitions: int
    """Its transitions."""
    decided_states: int
    """Explored states whose automaton state decides the formula."""
    bsccs: int
    """Recurrence classes (bottom strongly connected components)."""
    feasible_bsccs: int
    """The phi-feasible ones."""
    transient_states: int
    """Unknowns of the linear system."""
    solver: str
    """"lu" or "krylov"."""
    solver_reason: str
    """Why that solver was used."""
    solver_iterations: int
    """BiCGSTAB iterations (0 for LU)."""
    seconds: float
    """Wall-clock seconds."""
    defender_gradient: Optional[npt.NDArray[np.float64]]
    """dV/d mu_def, shaped like the defender's probabilities (zero off the
    support); with gradient=True."""
    adversary_gradient: Optional[npt.NDArray[np.float64]]
    """dV/d mu_adv, shaped like the adversary's probabilities."""
    defender_initial_gradient: Optional[npt.NDArray[np.float64]]
    """dV/d init_def, shape (nodes,)."""
    adversary_initial_gradient: Optional[npt.NDArray[np.float64]]
    """dV/d init_adv, shape (nodes,)."""

class RewardSolveResult:
    """The result of solve() for an expected-reward query (props=;
    docs/method.md section 9), with the names of its summary.json
    (docs/formats.md section 9)."""

    defender: Controller
    """The best defender found."""
    value: float
    """What it guarantees (inf where it is infinite): its expected reward,
    evaluated exactly, on a game without adversary; its certified worst
    case against every adversary on a game with one."""
    error_bound: float
    """A bound on |value - exact value| (docs/method.md section 8), or the
    width of the worst case's certified bracket."""
    certificate: Optional[dict[str, Any]]
    """As summary.json's: guaranteed, best_possible (what no defender beats:
    against the adversaries found, or seeing the state of a game without
    adversary), and the brackets worst_case and best_response."""
    query: Optional[Query]
    """The query restated in its own terms."""
    best_start: int
    """The start whose defender was returned."""
    starts: list[dict[str, Any]]
    """Each start's start (index), value, iterations, status and seconds."""
    dropped_starts: list[str]
    """The starts dropped for numerical trouble, with why."""
    curve: list[dict[str, Any]]
    """Every iteration's record of every start, then the returned one."""
    seconds: float
    """Wall-clock seconds."""

class SolveResult:
    """The result of solve(), with the names of summary.json
    (docs/formats.md section 9)."""

    defender: Controller
    """The best defender found."""
    adversary: Controller
    """The best response found to it."""
    certified: Optional[dict[str, float]]
    """{"certified_lower": ..., "upper_bound": ...}: the defender's value
    against every adversary is at least certified_lower, and no defender of
    any size does better than upper_bound; None when not certified."""
    certification_error: Optional[str]
    """Why `certified` is None."""
    query: Optional[Query]
    """With props=, the query restated in its own terms."""
    structure_used: str
    """The structure whose defender was kept."""
    worst_case: float
    """The best defender's worst-case estimate."""
    error_bound: float
    """The largest error bound of the values computed on that structure."""
    last_value: float
    """The value at that structure's last iterate."""
    structure_choice: list[str]
    """Why the best structure won, then why each other one lost."""
    curve: list[dict[str, Any]]
    """The best structure's iteration records (pandas.DataFrame(curve))."""
    curves: dict[str, list[dict[str, Any]]]
    """Every structure's records, by structure name."""
    structures: list[dict[str, Any]]
    """Every structure's report, as in summary.json."""
    sources: list[dict[str, Any]]
    """What each source of structures found, as in summary.json."""
    settings: dict[str, Any]
    """Every setting used, as in summary.json."""
    seconds: float
    """Wall-clock seconds of the whole job."""
    synthesis_seconds: float
    """Seconds of support synthesis."""

def example_grid(
    width: int = 3,
    height: int = 2,
    unsafe: Optional[Sequence[Union[int, str]]] = None,
    goal: Optional[Sequence[Union[int, str]]] = None,
    labels: Optional[dict[str, Sequence[Union[int, str]]]] = None,
    initial: Optional[Union[int, str]] = None,
    p_na: float = 0.8,
    p_a: float = 0.6,
    p_obs_defender: float = 0.8,
    p_obs_adversary: float = 0.6,
    observation: Literal["neighbourhood", "blind"] = "neighbourhood",
    random_unsafe: Optional[int] = None,
    seed: int = 0,
) -> Game:
    """The seed paper's grid family (`posg-fsc example grid`); the defaults
    are the paper's 3x2 instance (unsafe s4, goal s5, start s0). Cells are
    indices or names like "s4"."""

def solve(
    game: Game,
    ltl: Optional[str] = None,
    def_nodes: Optional[int] = None,
    adv_nodes: Optional[int] = None,
    *,
    props: Optional[Props] = None,
    defender: Optional[ControllerLike] = None,
    adversary: Optional[ControllerLike] = None,
    on_iteration: Optional[Callable[[dict[str, Any]], Optional[bool]]] = None,
    progress: Union[bool, float, None] = None,
    out: Optional[Path] = None,
    force: bool = False,
    **settings: Any,
) -> Union[SolveResult, RewardSolveResult]:
    """Tunes a defender against a worst-case adversary, as `posg-fsc solve`;
    for an expected-reward query (props=) the defender of def_nodes nodes
    that optimises it (a RewardSolveResult; on a game with an adversary,
    the one whose certified worst case is best).

    `settings` are the command line's options with _ for - and the same
    defaults (seed=0, max_iterations=3000, starts=4, structures=["full",
    "informed", "sat", "paper"], tolerance, solver, round, ...); an unknown
    keyword is a TypeError. on_iteration(record) gets each iteration's record (a dict)
    from the optimiser's threads; returning False stops the run, which then
    returns what it has; Ctrl-C stops it and raises KeyboardInterrupt.
    progress=True writes the command line's progress lines to sys.stderr
    while it runs (an event at once; the status, with the best certified
    bracket, when nothing happened for 5 s, or the seconds given instead of
    True). A misspelt keyword's TypeError suggests the closest one. With
    `out`, the solve directory is written there too (without `curve.svg`:
    plot `curve.csv` with matplotlib)."""

def sweep(
    game: Game,
    ltl: Optional[str] = None,
    def_nodes: Union[int, Sequence[int], range, None] = None,
    adv_nodes: Union[int, Sequence[int], range, None] = None,
    *,
    props: Optional[Props] = None,
    on_iteration: Optional[Callable[[dict[str, Any]], Optional[bool]]] = None,
    progress: Union[bool, float, None] = None,
    **settings: Any,
) -> list[dict[str, Any]]:
    """solve() for every size pair, as `posg-fsc sweep` (defaults 1..3 and
    1..2): defender sizes increasing, each warm-started from the next smaller
    one and kept at least as good. One dict per pair with the columns of
    sweep.csv (with `result`, the row in words) and the pair's SolveResult under "solved".
    on_iteration and progress are solve()'s, for each pair (progress lines
    begin with the pair and count the seconds since the sweep began)."""

def settings() -> list[dict[str, Any]]:
    """Every setting solve and sweep take as a keyword: a dict with keyword,
    default and meaning (the command line's --help text); help(solve) and
    help(sweep) list them too."""

def simulate(
    game: Game,
    ltl: Optional[str] = None,
    *,
    props: Optional[Props] = None,
    defender: Optional[ControllerLike] = None,
    adversary: Optional[ControllerLike] = None,
    runs: int = 10000,
    seed: int = 0,
    allow_unused_propositions: bool = False,
) -> dict[str, Any]:
    """A Monte Carlo estimate of the controllers' value checked against the
    exact value, as `posg-fsc simulate`: formula, settings, estimate (mean,
    lower, upper, confidence, ...), exact_value, exact_within_interval,
    seconds. For an expected-reward query of props=, the mean total reward
    until the target. A 95% interval misses the exact value about once in
    twenty seeds; a UserWarning says so when it does."""

def certify(
    game: Game,
    ltl: Optional[str] = None,
    defender: Optional[ControllerLike] = None,
    adversary: Optional[ControllerLike] = None,
    *,
    props: Optional[Props] = None,
) -> dict[str, Any]:
    """The certified bounds of `posg-fsc certify`: "lower" (the defender's
    guaranteed value against every adversary) and "upper" (the best any
    defender does against `adversary`, None without one); each a dict with
    value, mdp_states, seconds, residual, error_bound. "belief": for a
    one-player game, the best any defender of any memory does (a dict with
    value, beliefs, complete), else None. For an expected-reward query
    (props=), the reward's certificate as `posg-fsc certify` prints it:
    query, minimise, guaranteed (against every adversary), best_possible
    (against `adversary`, else None), worst_case and best_response."""

def support(
    game: Game,
    ltl: Optional[str] = None,
    def_nodes: Optional[int] = None,
    almost_sure: bool = False,
    *,
    props: Optional[Props] = None,
    **settings: Any,
) -> dict[str, Any]:
    """A defender support that wins positively (or almost surely) against
    every adversary, by SAT, as `posg-fsc support`: the fields of
    support.json and "defender", the uniform Controller on it (or None)."""

def translate(ltl: str) -> str:
    """The deterministic Rabin automaton of an LTL formula in HOA, as
    `posg-fsc translate --hoa`."""
