//! Writes the seed paper's 3x2 grid with both observation models and, as
//! controls, with exact observations (`p_obs = 1` for both players) and with
//! exact observations and moves that always succeed (`p_NA = p_A = 1`), using
//! the crate's own generator (`GridSpec`), into the directory given as argument.

use posg_fsc::game::file::write;
use posg_fsc::game::grid::{GridSpec, ObservationModel};
use std::path::Path;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let dir = std::env::args().nth(1).ok_or("usage: make_grids DIR")?;
    let exact = GridSpec { defender_p_obs: 1.0, adversary_p_obs: 1.0, ..GridSpec::default() };
    for (name, spec) in [
        ("grid-3x2.posg.json", GridSpec::default()),
        ("grid-3x2-blind.posg.json", GridSpec { observation: ObservationModel::Blind, ..GridSpec::default() }),
        ("grid-3x2-exact.posg.json", exact.clone()),
        ("grid-3x2-exact-sure.posg.json", GridSpec { p_na: 1.0, p_a: 1.0, ..exact }),
    ] {
        let game = spec.build()?;
        write(&Path::new(&dir).join(name), &game)?;
    }
    Ok(())
}
