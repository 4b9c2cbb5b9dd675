//! Arguments and loaders shared by several subcommands.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::Context;
use clap::Args;
use posg_fsc::automaton::Dra;
use posg_fsc::automaton::read_hoa_dra;
use posg_fsc::controller::{Fsc, Role};
use posg_fsc::game::Posg;
use posg_fsc::game::drn::DrnOptions;
use posg_fsc::ltl::props::{Property, Query};
use posg_fsc::output::{PlotFormat, PlotSize};
use posg_fsc::pipeline::{Automata, PipelineError, RewardObjective};
use posg_fsc::value::{DEFAULT_LU_LIMIT, DEFAULT_TOLERANCE, SolverMethod, SolverSettings};
use serde::Serialize;

/// The objective: an LTL formula, a property file or a deterministic
/// automaton in HOA.
#[derive(Debug, Clone, Args)]
pub struct ObjectiveArgs {
    /// The LTL formula phi, in Spot's syntax (e.g. 'GF goal & G !unsafe').
    #[arg(
        long,
        required_unless_present_any = ["automaton", "props"],
        conflicts_with_all = ["automaton", "props"]
    )]
    pub ltl: Option<String>,
    /// A Storm/PRISM property file with one query `<<P>> Pmax=? [ PATH ]`
    /// (phi = PATH) or `<<P>> Pmin=? [ PATH ]` (phi = !PATH, e.g. `G !goal`),
    /// instead of --ltl, or the query itself (recognised by its `=?`, as
    /// Python's props=: `--props 'Pmax=? [F "goal"]'`); for a turn-based
    /// DRN game, player P is the defender (docs/formats.md section 6).
    /// `eval`, `simulate`, `certify` and `solve` also take an
    /// expected-reward query `R{"r"}min=? [ F T ]` or `R{"r"}max=? [ F T ]`
    /// (docs/method.md section 9).
    #[arg(long, value_name = "FILE.props", conflicts_with = "automaton")]
    pub props: Option<PathBuf>,
    /// A deterministic automaton for phi in HOA v1 or v1.1 (instead of
    /// --ltl; docs/formats.md section 4).
    #[arg(long, value_name = "FILE.hoa")]
    pub automaton: Option<PathBuf>,
    /// Accept a formula that can never hold because a proposition labels no
    /// state of the game (by default that is an error: usually a misspelling).
    #[arg(long)]
    pub allow_unused_propositions: bool,
    /// Time budget of the translation of --ltl (and of its negation) into an
    /// automaton, in seconds; a formula that needs more is an error naming
    /// the subformula that blew up.
    #[arg(long, default_value_t = posg_fsc::ltl::DEFAULT_TRANSLATION_SECONDS, value_parser = posg_fsc::seconds::parse_positive)]
    pub translate_seconds: f64,
}

impl ObjectiveArgs {
    /// The query of `--props`, if given.
    pub fn property(&self) -> anyhow::Result<Option<Property>> {
        self.props.as_deref().map(read_props).transpose()
    }

    /// The text of phi: `--ltl`, or the objective of `--props`; `None` for
    /// `--automaton`. An expected-reward query is an error: the commands
    /// that take one (`eval`, `simulate`, `certify`, `solve`) ask
    /// [`Self::reward_objective`] first.
    pub fn formula_text(&self) -> anyhow::Result<Option<String>> {
        if let Some(text) = &self.ltl {
            return Ok(Some(text.clone()));
        }
        let Some(property) = self.property()? else {
            return Ok(None);
        };
        match property.probability_objective() {
            Some(objective) => Ok(Some(objective.to_string())),
            None => anyhow::bail!(
                "{}: `{}` is an expected-reward query: `posg-fsc eval` computes its value for \
                 given controllers, `simulate` estimates it, `certify` bounds it against every \
                 adversary and `solve` optimises it; this command takes probability queries \
                 (`Pmax=?`, `Pmin=?`) so far (docs/method.md section 9)",
                property.position(&self.props_name()),
                property.text
            ),
        }
    }

    /// The expected-reward objective of `--props` on `game`, when its query
    /// is one (its warnings on stderr); `None` for any other objective.
    pub fn reward_objective(&self, game: &Posg) -> anyhow::Result<Option<RewardObjective>> {
        let Some(property) = self.property()? else {
            return Ok(None);
        };
        let Query::Reward(query) = &property.query else {
            return Ok(None);
        };
        let budget = posg_fsc::ltl::TranslationBudget {
            seconds: self.translate_seconds,
        };
        let minimise = !property.maximise;
        let allow = self.allow_unused_propositions;
        let at = property.position(&self.props_name());
        match RewardObjective::for_game(game, query, minimise, &budget, allow) {
            Ok((objective, warnings)) => {
                print_warnings(&warnings);
                Ok(Some(objective))
            }
            Err(PipelineError::Propositions(check)) => {
                print_warnings(&check.warnings);
                Err(anyhow::anyhow!("{at}: {}", check.error.unwrap_or_default()))
            }
            Err(error) => Err(anyhow::anyhow!("{at}: {error}")),
        }
    }

    /// The property file's name as errors show it.
    fn props_name(&self) -> String {
        self.props.as_deref().map(props_name).unwrap_or_default()
    }

    /// The automaton of `formula` within the translation budget.
    pub fn translate(&self, formula: &posg_fsc::ltl::Formula) -> anyhow::Result<Dra> {
        let budget = posg_fsc::ltl::TranslationBudget {
            seconds: self.translate_seconds,
        };
        Ok(posg_fsc::ltl::translate_within(formula, &budget)?)
    }
}

/// The query of the property file at `path`, or of the query given inline
/// in its place ([`is_inline_query`]).
pub fn read_props(path: &Path) -> anyhow::Result<Property> {
    if is_inline_query(path) {
        let text = path.to_string_lossy();
        return Ok(posg_fsc::ltl::props::from_props_str(&text, "--props")?);
    }
    let text =
        std::fs::read_to_string(path).with_context(|| format!("cannot read {}", path.display()))?;
    Ok(posg_fsc::ltl::props::from_props_str(
        &text,
        &path.display().to_string(),
    )?)
}

/// Whether `--props` gave the query itself: no file of that name, and an
/// `=?` in it (as Python's props= tells a query from a path).
fn is_inline_query(given: &Path) -> bool {
    !given.exists() && given.to_string_lossy().contains("=?")
}

/// The name `--props` is cited by in messages: the file's, or `--props`
/// for a query given inline.
fn props_name(given: &Path) -> String {
    match is_inline_query(given) {
        true => "--props".to_string(),
        false => given.display().to_string(),
    }
}

/// The two controllers.
#[derive(Debug, Clone, Args)]
pub struct ControllerArgs {
    /// The defender's controller: a *.fsc.json file (docs/formats.md section
    /// 2) or `uniform:K` (K nodes, uniform over all (next node, enabled
    /// action) pairs, starting in node 0).
    #[arg(long, default_value = "uniform:1")]
    pub defender: String,
    /// The adversary's controller, as for --defender (`uniform:1` for a POMDP).
    #[arg(long, default_value = "uniform:1")]
    pub adversary: String,
}

/// The plots' file format and size (`solve`, `sweep`, `sweep-merge`).
#[derive(Debug, Clone, Copy, Args)]
pub struct PlotArgs {
    /// The plots' file format: `svg` (curve.svg, sweep.svg) or `png`
    /// (curve.png, sweep.png, for slides).
    #[arg(long, default_value = "svg", value_parser = plot_format)]
    pub format: PlotFormat,
    /// The plots' size, WIDTHxHEIGHT: pixels of a PNG image, or the SVG
    /// canvas in the same units.
    #[arg(long, default_value_t = PlotSize::default(), value_parser = plot_size)]
    pub size: PlotSize,
    /// The resolution a PNG records, in dots per inch: it prints
    /// WIDTH / DPI inches wide (SVG ignores it).
    #[arg(long, default_value_t = PlotSize::DEFAULT_DPI, value_parser = clap::value_parser!(u32).range(10..=2400))]
    pub dpi: u32,
}

impl PlotArgs {
    /// The plots' size with its resolution.
    pub fn picture(&self) -> PlotSize {
        PlotSize {
            dpi: self.dpi,
            ..self.size
        }
    }
}

fn plot_format(text: &str) -> Result<PlotFormat, String> {
    text.parse()
}

fn plot_size(text: &str) -> Result<PlotSize, String> {
    text.parse()
}

/// How the linear systems are solved (`eval`, `solve`, `sweep`).
#[derive(Debug, Clone, Args)]
pub struct SolverArgs {
    /// `lu` (sparse LU, direct), `krylov` (BiCGSTAB with an ILU(0)
    /// preconditioner, iterative, warm-started) or `auto` (LU up to
    /// --lu-limit unknowns unless its analysis predicts a costly
    /// factorisation; there and above the limit, a short BiCGSTAB trial
    /// predicts whether krylov costs less than LU; eval reports why as
    /// `solver_reason`).
    #[arg(long, default_value = "auto", value_parser = solver_method)]
    pub solver: SolverMethod,
    /// With --solver auto: the most unknowns |T| solved by LU.
    #[arg(long, default_value_t = DEFAULT_LU_LIMIT)]
    pub lu_limit: usize,
    /// Largest accepted residual max |(I - Q) x - b| of a linear solve
    /// (`--solver-tolerance` is an old name of it).
    #[arg(long, alias = "solver-tolerance", default_value_t = DEFAULT_TOLERANCE, value_parser = positive_tolerance)]
    pub tolerance: f64,
}

impl SolverArgs {
    /// The library's settings.
    pub fn settings(&self) -> SolverSettings {
        SolverSettings {
            method: self.solver,
            tolerance: self.tolerance,
            lu_limit: self.lu_limit,
            ..SolverSettings::default()
        }
    }
}

fn solver_method(text: &str) -> Result<SolverMethod, String> {
    text.parse()
}

/// Parses a tolerance: a finite number greater than 0.
pub fn positive_tolerance(text: &str) -> Result<f64, String> {
    match text.parse::<f64>() {
        Ok(t) if t.is_finite() && t > 0.0 => Ok(t),
        _ => Err(format!("'{text}' is not a finite number greater than 0")),
    }
}

/// Reads and validates a game file: JSON, binary, or a model in Storm's
/// DRN format (imported as `import-drn` does, with player 0 the defender of
/// a turn-based game; docs/formats.md section 6).
pub fn read_game(path: &Path) -> anyhow::Result<Posg> {
    read_game_as(path, &DrnOptions::default())
}

/// [`read_game`] for a command with an objective: the player `<<P>>` of a
/// `--props` query is the defender of a turn-based DRN game.
pub fn read_game_for(path: &Path, objective: &ObjectiveArgs) -> anyhow::Result<Posg> {
    let property = objective.property()?;
    let props = objective.props.as_deref();
    read_game_as(path, &drn_options(props.zip(property.as_ref())))
}

/// The import options of a DRN game for the query of the property file,
/// if any: its player `<<P>>` is the defender, and errors about that
/// player name the file, line and column of `<<P>>`.
pub fn drn_options(query: Option<(&Path, &Property)>) -> DrnOptions {
    let Some((file, property)) = query.filter(|(_, p)| p.player.is_some()) else {
        return DrnOptions::default();
    };
    DrnOptions {
        defender_player: property.player,
        defender_source: Some(property.position(&file.display().to_string())),
    }
}

/// Reads a game; a DRN model (recognised by its content) is imported with
/// `options`, its warnings on stderr.
fn read_game_as(path: &Path, options: &DrnOptions) -> anyhow::Result<Posg> {
    let bytes = std::fs::read(path).with_context(|| format!("cannot read {}", path.display()))?;
    if !posg_fsc::game::drn::is_drn(&bytes) {
        if let (Some(player), Some(source)) = (options.defender_player, &options.defender_source) {
            eprintln!(
                "warning: {source}: `<<{player}>>` is ignored: the game file {} fixes its \
                 defender (docs/formats.md section 6)",
                path.display()
            );
        }
        return Ok(posg_fsc::game::file::read(path)?);
    }
    let import = posg_fsc::game::drn::read_with(path, options)?;
    for warning in &import.warnings {
        eprintln!("warning: {warning}");
    }
    Ok(import.game)
}

/// The automaton for the objective, with a description of where it came
/// from. Warns on stderr about propositions that label no state of the game
/// (they are false everywhere: docs/formats.md section 3), with the closest
/// proposition of the game as a hint; when the objective is then
/// unsatisfiable (every value would be 0) that is an error unless
/// `--allow-unused-propositions`.
pub fn objective(args: &ObjectiveArgs, game: &Posg) -> anyhow::Result<(Dra, String)> {
    match (&args.formula_text()?, &args.automaton) {
        (Some(text), _) => {
            let automata = formula_automata(args, game, text, false)?;
            Ok((automata.phi, automata.description))
        }
        (None, Some(path)) => {
            let text = std::fs::read_to_string(path)
                .with_context(|| format!("cannot read {}", path.display()))?;
            let dra = read_hoa_dra(&text).with_context(|| format!("in {}", path.display()))?;
            let description = path.display().to_string();
            check_propositions(&dra, game, &description, args.allow_unused_propositions)?;
            Ok((dra, description))
        }
        (None, None) => anyhow::bail!("give --ltl, --props or --automaton"),
    }
}

/// The automata of the formula `text` (and of its negation when
/// `negation`) within `--translate-seconds`, checked against the game's
/// propositions ([`Automata::for_game`]), the check's warnings on stderr.
pub fn formula_automata(
    args: &ObjectiveArgs,
    game: &Posg,
    text: &str,
    negation: bool,
) -> anyhow::Result<Automata> {
    let budget = posg_fsc::ltl::TranslationBudget {
        seconds: args.translate_seconds,
    };
    let allow = args.allow_unused_propositions;
    match Automata::for_game(game, text, &budget, negation, allow) {
        Ok((automata, warnings)) => {
            print_warnings(&warnings);
            Ok(automata)
        }
        Err(PipelineError::Propositions(check)) => {
            print_warnings(&check.warnings);
            Err(anyhow::Error::msg(check.error.unwrap_or_default()))
        }
        Err(error @ PipelineError::Parse(_)) => {
            Err(anyhow::Error::new(error).context(format!("in the formula '{text}'")))
        }
        Err(error) => Err(error.into()),
    }
}

/// Each warning on stderr, as `warning: ...`.
fn print_warnings(warnings: &[String]) {
    for warning in warnings {
        eprintln!("warning: {warning}");
    }
}

/// Warns about each proposition of `dra` that labels no state of the game
/// (with a `did you mean` hint) and refuses an objective that those
/// propositions, false everywhere, make unsatisfiable, unless `allow`
/// ([`posg_fsc::pipeline::check_propositions`]).
pub fn check_propositions(
    dra: &Dra,
    game: &Posg,
    objective: &str,
    allow: bool,
) -> anyhow::Result<()> {
    let check = posg_fsc::pipeline::check_propositions(dra, game, objective, allow);
    print_warnings(&check.warnings);
    match check.error {
        Some(error) => Err(anyhow::Error::msg(error)),
        None => Ok(()),
    }
}

/// The automaton for `!phi`: translated from `--ltl`, or read from
/// `negated_automaton` when phi was given as `--automaton`.
pub fn negated_objective(
    objective: &ObjectiveArgs,
    negated_automaton: Option<&Path>,
    game: &Posg,
) -> anyhow::Result<Dra> {
    if let Some(text) = &objective.formula_text()? {
        let phi = posg_fsc::ltl::parse(text).with_context(|| format!("in the formula '{text}'"))?;
        return objective
            .translate(&phi.negate())
            .context("translating !phi");
    }
    let path = negated_automaton.ok_or_else(|| {
        anyhow::anyhow!(
            "with --automaton, give --negated-automaton (an automaton for !phi): certification needs it"
        )
    })?;
    let text =
        std::fs::read_to_string(path).with_context(|| format!("cannot read {}", path.display()))?;
    let dra = read_hoa_dra(&text).with_context(|| format!("in {}", path.display()))?;
    if dra
        .propositions()
        .iter()
        .any(|p| !game.propositions().contains(p))
    {
        eprintln!(
            "warning: the negated automaton uses propositions that label no state of the game"
        );
    }
    Ok(dra)
}

/// Both controllers, read or built from their specifications.
pub fn controllers(args: &ControllerArgs, game: &Posg) -> anyhow::Result<(Fsc, Fsc)> {
    let defender = posg_fsc::controller::file::resolve(&args.defender, game, Role::Defender)?;
    let adversary = posg_fsc::controller::file::resolve(&args.adversary, game, Role::Adversary)?;
    Ok((defender, adversary))
}

/// What every JSON report records about the run that made it.
#[derive(Debug, Serialize)]
pub struct Provenance {
    /// The command line.
    pub command: Vec<String>,
    /// `posg-fsc`'s version.
    pub version: &'static str,
}

/// The current process's command line for the record, an argument that is
/// not UTF-8 (a path is any bytes on Unix) with its bad bytes shown as
/// U+FFFD (`std::env::args` would panic on it).
pub fn command_line() -> Vec<String> {
    std::env::args_os()
        .map(|argument| argument.to_string_lossy().into_owned())
        .collect()
}

impl Provenance {
    /// The current process's command line and the crate version.
    pub fn current() -> Self {
        Self {
            command: command_line(),
            version: env!("CARGO_PKG_VERSION"),
        }
    }
}

/// Prints a value as pretty JSON on stdout.
pub fn print_json(value: &impl Serialize) -> anyhow::Result<()> {
    print_text(&format!("{}\n", serde_json::to_string_pretty(value)?))
}

/// Writes text to stdout; a closed pipe (`posg-fsc ... | head`) is an
/// `io::Error` of kind `BrokenPipe`, which `main` treats as a normal end.
pub fn print_text(text: &str) -> anyhow::Result<()> {
    use std::io::Write;
    let mut stdout = std::io::stdout().lock();
    stdout.write_all(text.as_bytes())?;
    stdout.flush()?;
    Ok(())
}

/// Seconds since `start`.
pub fn seconds_since(start: Instant) -> f64 {
    start.elapsed().as_secs_f64()
}
