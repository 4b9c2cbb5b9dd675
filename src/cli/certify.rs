//! `posg-fsc certify`: the two certified bounds of method.md section 6 for
//! a defender controller and, optionally, an adversary controller.
//!
//! Prints one JSON object: `lower` is the defender's guaranteed probability
//! of the formula against every adversary (of any size, observation and
//! memory); `upper` (null without `--adversary`) is the best probability any
//! defender achieves against the given adversary. The strategies behind them
//! are written to files on request (`--attack`, `--response`).

use std::path::{Path, PathBuf};

use anyhow::Context;
use clap::Args;
use serde_json::json;

use posg_fsc::certify::{Bound, lower_bound, upper_bound};
use posg_fsc::controller::{Role, file::resolve};
use posg_fsc::game::file::read;
use posg_fsc::ltl;

/// Arguments of `certify`.
#[derive(Debug, Args)]
pub struct CertifyArgs {
    /// The game (`*.posg.json`).
    game: PathBuf,
    /// The LTL formula phi (Spot syntax).
    #[arg(long)]
    ltl: String,
    /// The defender's controller: a `*.fsc.json` file or `uniform:K`.
    #[arg(long)]
    defender: String,
    /// The adversary's controller for the upper bound: a file or `uniform:K`.
    #[arg(long)]
    adversary: Option<String>,
    /// Write the adversary's optimal strategy against the defender (JSON) here.
    #[arg(long)]
    attack: Option<PathBuf>,
    /// Write the defender's optimal strategy against the adversary (JSON) here.
    #[arg(long)]
    response: Option<PathBuf>,
}

/// Computes and prints the bounds.
pub fn run(args: CertifyArgs) -> anyhow::Result<()> {
    let game = read(&args.game)?;
    let phi = ltl::parse(&args.ltl).with_context(|| format!("formula {:?}", args.ltl))?;
    for name in phi.propositions() {
        if !game.propositions().contains(&name) {
            eprintln!(
                "warning: proposition {name} labels no state of the game; it is false everywhere"
            );
        }
    }
    let defender = resolve(&args.defender, &game, Role::Defender)?;
    let not_phi_dra = ltl::translate(&phi.negate()).context("translating !phi")?;
    let lower = lower_bound(&game, &not_phi_dra, &defender)?;
    write_strategy(args.attack.as_deref(), &lower)?;
    let upper = match &args.adversary {
        Some(spec) => {
            let adversary = resolve(spec, &game, Role::Adversary)?;
            let phi_dra = ltl::translate(&phi).context("translating phi")?;
            let upper = upper_bound(&game, &phi_dra, &adversary)?;
            write_strategy(args.response.as_deref(), &upper)?;
            Some(upper)
        }
        None => None,
    };
    let report = json!({
        "game": args.game.display().to_string(),
        "ltl": phi.to_string(),
        "lower": summary(&lower),
        "upper": upper.as_ref().map(summary),
    });
    println!("{}", serde_json::to_string_pretty(&report)?);
    Ok(())
}

/// A bound without its strategy.
fn summary(bound: &Bound) -> serde_json::Value {
    json!({
        "value": bound.value,
        "mdp_states": bound.mdp_states,
        "seconds": bound.seconds,
        "residual": bound.residual,
    })
}

fn write_strategy(path: Option<&Path>, bound: &Bound) -> anyhow::Result<()> {
    if let Some(path) = path {
        let text = serde_json::to_string_pretty(&bound.strategy)?;
        std::fs::write(path, text).with_context(|| format!("writing {}", path.display()))?;
    }
    Ok(())
}
