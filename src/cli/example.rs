//! `posg-fsc example`: built-in example games, written as *.posg.json (or,
//! with `--binary`, as *.posg.bin).

use std::path::PathBuf;

use anyhow::Context;
use clap::{Args, Subcommand, ValueEnum};
use posg_fsc::game::grid::{GridSpec, ObservationModel, RandomUnsafe};

/// Arguments of `example`.
#[derive(Debug, Args)]
pub struct ExampleArgs {
    #[command(subcommand)]
    example: Example,
}

#[derive(Debug, Subcommand)]
enum Example {
    /// The seed paper's grid family: a W x H grid, cell i = x + W*y named s{i};
    /// defender actions R, L, U, D move to the neighbouring cell with
    /// probability p_NA (no attack) or p_A (attack) and otherwise slip to
    /// {s} ∪ N(s); adversary actions A and NA. Defaults give the paper's
    /// 3x2 instance (unsafe s4, goal s5, start s0).
    Grid(GridArgs),
}

/// The grid's options; cells are given as `s{i}` or `i`, comma-separated
/// (`none` for no cell).
#[derive(Debug, Args)]
struct GridArgs {
    /// Number of columns W.
    #[arg(long, default_value_t = 3)]
    width: usize,
    /// Number of rows H.
    #[arg(long, default_value_t = 2)]
    height: usize,
    /// Cells labelled `unsafe`.
    #[arg(long = "unsafe", default_value = "s4", value_parser = parse_cells)]
    unsafe_cells: CellList,
    /// Cells labelled `goal`.
    #[arg(long, default_value = "s5", value_parser = parse_cells)]
    goal: CellList,
    /// More labels, `NAME=CELLS` (e.g. `--label a=s3,s7`); repeatable.
    #[arg(long, value_parser = parse_label)]
    label: Vec<(String, CellList)>,
    /// The initial cell (probability 1).
    #[arg(long, default_value = "s0", value_parser = parse_cell)]
    initial: usize,
    /// Add this many unsafe cells at random (never the initial cell or a goal).
    #[arg(long)]
    random_unsafe: Option<usize>,
    /// Seed for --random-unsafe (ChaCha8).
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Probability of the intended move when the adversary does not attack.
    #[arg(long, default_value_t = 0.8)]
    p_na: f64,
    /// Probability of the intended move when the adversary attacks.
    #[arg(long, default_value_t = 0.6)]
    p_a: f64,
    /// Probability that the defender observes its true cell.
    #[arg(long, default_value_t = 0.8)]
    p_obs_defender: f64,
    /// Probability that the adversary observes the true cell.
    #[arg(long, default_value_t = 0.6)]
    p_obs_adversary: f64,
    /// `neighbourhood`: observe a cell name, the true one with p_obs, else a
    /// uniformly random neighbour; `blind`: the paper's two symbols
    /// {correct, wrong}.
    #[arg(long, value_enum, default_value_t = Observation::Neighbourhood)]
    observation: Observation,
    /// Write the game here instead of standard output.
    #[arg(long)]
    out: Option<PathBuf>,
    /// Write the binary form `*.posg.bin` (docs/formats.md section 11), which
    /// every command reads like the JSON file and much faster; needs --out.
    #[arg(long, requires = "out")]
    binary: bool,
}

#[derive(Debug, Clone, Copy, ValueEnum)]
enum Observation {
    Neighbourhood,
    Blind,
}

#[derive(Debug, Clone)]
struct CellList(Vec<usize>);

fn parse_cell(text: &str) -> Result<usize, String> {
    let digits = text.strip_prefix('s').unwrap_or(text);
    digits
        .parse()
        .map_err(|_| format!("'{text}' is not a cell (expected s<index> or <index>)"))
}

fn parse_cells(text: &str) -> Result<CellList, String> {
    if text.is_empty() || text == "none" {
        return Ok(CellList(Vec::new()));
    }
    text.split(',')
        .map(parse_cell)
        .collect::<Result<_, _>>()
        .map(CellList)
}

fn parse_label(text: &str) -> Result<(String, CellList), String> {
    let (name, cells) = text
        .split_once('=')
        .ok_or_else(|| format!("'{text}' is not NAME=CELLS"))?;
    Ok((name.to_string(), parse_cells(cells)?))
}

/// Runs `example`.
pub fn run(args: ExampleArgs) -> anyhow::Result<()> {
    let Example::Grid(grid) = args.example;
    let spec = GridSpec {
        width: grid.width,
        height: grid.height,
        unsafe_cells: grid.unsafe_cells.0,
        goal_cells: grid.goal.0,
        extra_labels: grid
            .label
            .into_iter()
            .map(|(name, cells)| (name, cells.0))
            .collect(),
        initial: grid.initial,
        p_na: grid.p_na,
        p_a: grid.p_a,
        defender_p_obs: grid.p_obs_defender,
        adversary_p_obs: grid.p_obs_adversary,
        observation: match grid.observation {
            Observation::Neighbourhood => ObservationModel::Neighbourhood,
            Observation::Blind => ObservationModel::Blind,
        },
        random_unsafe: grid.random_unsafe.map(|count| RandomUnsafe {
            count,
            seed: grid.seed,
        }),
    };
    let game = spec.build()?;
    if grid.binary {
        let path = grid.out.expect("clap requires --out with --binary");
        return Ok(posg_fsc::game::binary::write(&path, &game)?);
    }
    let text = posg_fsc::game::file::to_json_string(&game);
    match grid.out {
        Some(path) => {
            std::fs::write(&path, text).with_context(|| format!("cannot write {}", path.display()))
        }
        None => super::common::print_text(&format!("{text}\n")),
    }
}
