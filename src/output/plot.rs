//! What the plots show, as plain data: [`PlotFormat`], [`Title`],
//! [`CurvePlot`] (`curve.svg`) and [`SweepPoint`] (`sweep.svg`). The
//! drawing ([`plot_curve`], [`plot_sweep`], module `draw`) needs the cargo
//! feature `plot` (plotters); without it they return an error.

use std::fmt;
use std::path::Path;
use std::str::FromStr;

use super::OutputError;
use crate::certify::Bracket;
use crate::optimise::IterationRecord;

#[cfg(feature = "plot")]
mod draw;

/// The file format of the plots `solve` and `sweep` write (`--format`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum PlotFormat {
    /// Scalable vector graphics, text kept as text (the default).
    #[default]
    Svg,
    /// A PNG image (for slides; 900 x 520 pixels unless a [`PlotSize`]
    /// says otherwise).
    Png,
}

impl PlotFormat {
    /// The file name extension: `svg` or `png`.
    pub fn extension(self) -> &'static str {
        match self {
            Self::Svg => "svg",
            Self::Png => "png",
        }
    }
}

impl fmt::Display for PlotFormat {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.extension())
    }
}

impl FromStr for PlotFormat {
    type Err = String;

    fn from_str(text: &str) -> Result<Self, String> {
        match text {
            "svg" => Ok(Self::Svg),
            "png" => Ok(Self::Png),
            _ => Err(format!("'{text}' is not a plot format: svg or png")),
        }
    }
}

/// The size of a plot (`--size WIDTHxHEIGHT`): pixels of a PNG image, or
/// the SVG canvas in the same units; 900 x 520 by default. Read from and
/// written as `WIDTHxHEIGHT`, with the default resolution.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PlotSize {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// The resolution a PNG image records (`--dpi`, its `pHYs` chunk): it
    /// prints `width / dpi` inches wide. SVG ignores it.
    pub dpi: u32,
}

impl PlotSize {
    /// The smallest size the legend, title and axes fit in.
    pub const MIN: PlotSize = PlotSize {
        width: 640,
        height: 400,
        dpi: Self::DEFAULT_DPI,
    };
    /// The largest size (a PNG of it is drawn in about 100 MB of memory).
    pub const MAX: PlotSize = PlotSize {
        width: 6000,
        height: 6000,
        dpi: Self::DEFAULT_DPI,
    };
    /// The resolution recorded unless `--dpi` says otherwise.
    pub const DEFAULT_DPI: u32 = 96;
}

impl Default for PlotSize {
    fn default() -> Self {
        Self {
            width: 900,
            height: 520,
            dpi: Self::DEFAULT_DPI,
        }
    }
}

impl fmt::Display for PlotSize {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}x{}", self.width, self.height)
    }
}

impl FromStr for PlotSize {
    type Err = String;

    fn from_str(text: &str) -> Result<Self, String> {
        let (min, max) = (Self::MIN, Self::MAX);
        let bad = || {
            format!(
                "'{text}' is not a plot size: WIDTHxHEIGHT in pixels, from {min} to {max} (e.g. \
                 1200x700)"
            )
        };
        let (width, height) = text.split_once(['x', 'X']).ok_or_else(bad)?;
        let size = Self {
            width: width.trim().parse().map_err(|_| bad())?,
            height: height.trim().parse().map_err(|_| bad())?,
            dpi: Self::DEFAULT_DPI,
        };
        let within = |v: u32, lo: u32, hi: u32| (lo..=hi).contains(&v);
        if within(size.width, min.width, max.width) && within(size.height, min.height, max.height) {
            Ok(size)
        } else {
            Err(bad())
        }
    }
}

/// A plot's title: the first line (e.g. game and formula) and the second
/// (sizes, structure).
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct Title {
    /// The first, larger line.
    pub main: String,
    /// The second, smaller line (may be empty).
    pub detail: String,
}

/// What a structure returned, as `solve` prints it and `summary.json`
/// holds it: drawn right of the curve's last iterate.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Returned {
    /// The returned defender's worst-case estimate.
    pub worst_case: f64,
    /// Its certified bracket (method.md section 6), when computed.
    pub certified: Option<Bracket>,
    /// What `worst_case` is where no bracket is drawn; the legend says it.
    pub kind: ReturnedValue,
}

/// What a returned defender's single value is ([`Returned::worst_case`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ReturnedValue {
    /// A best-response estimate of its worst case.
    Estimated,
    /// Its exact value (a game without adversary: an expected reward,
    /// method.md section 9).
    Exact,
    /// What it guarantees against every adversary, certified (an expected
    /// reward on a game with an adversary, method.md section 9).
    Guaranteed,
}

/// `curve.svg` of one structure: the shaded band `[certified lower bound,
/// game upper bound]` at the best-response checks (where computed), its
/// two edges, the value `V(phi_def(t), phi_adv)` and the worst-case
/// estimate, against the iteration (integer ticks), and right of the last
/// iterate the returned defender's certified bracket (or its estimate);
/// optionally a second axis on top with the seconds elapsed.
#[derive(Debug, Clone, Copy)]
pub struct CurvePlot<'a> {
    /// The title.
    pub title: &'a Title,
    /// The records of the structure's kept start, in iteration order.
    pub records: &'a [IterationRecord],
    /// What the structure returned (`None`: it was dropped for numerical
    /// trouble).
    pub returned: Option<Returned>,
    /// Whether to draw the top axis with the seconds elapsed.
    pub seconds_axis: bool,
    /// The picture's size.
    pub size: PlotSize,
    /// What the value axis measures ([`PROBABILITY_AXIS`], or an expected
    /// reward's name and direction, [`reward_axis`]).
    pub quantity: &'a str,
    /// Whether lower values are better (a minimised expected cost): the
    /// iterate that found the returned defender is then the lowest.
    pub minimise: bool,
}

/// The value axis of a probability objective's curve.
pub const PROBABILITY_AXIS: &str = "probability of phi";

/// The value axis of an expected-reward objective's curve (method.md
/// section 9): the reward model's name (`None` for a game's only one) and
/// whether the defender minimises it, e.g. `expected reward "steps",
/// minimised`.
pub fn reward_axis(name: Option<&str>, minimise: bool) -> String {
    let direction = if minimise { "minimised" } else { "maximised" };
    match name {
        Some(name) => format!("expected reward \"{name}\", {direction}"),
        None => format!("expected reward, {direction}"),
    }
}

/// One row of a sweep: sizes and the worst-case estimate.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SweepPoint {
    /// Defender nodes.
    pub defender_nodes: usize,
    /// Adversary nodes.
    pub adversary_nodes: usize,
    /// The best defender's worst-case estimate.
    pub worst_case: f64,
    /// The certified bracket (method.md section 6), when computed: the
    /// defender's value against every adversary and the game upper bound.
    pub bracket: Option<(f64, f64)>,
}

/// Draws `curve` into `path` as `format`.
pub fn plot_curve(path: &Path, format: PlotFormat, curve: &CurvePlot) -> Result<(), OutputError> {
    #[cfg(feature = "plot")]
    return draw::curve(path, format, curve);
    #[cfg(not(feature = "plot"))]
    {
        let _ = (format, curve);
        Err(not_built(path))
    }
}

/// Draws `sweep.svg` into `path` as `format`, `size` big: a heatmap with one cell per
/// (defender size, adversary size), coloured by the certified lower bound
/// (or, without certification, by the worst-case estimate) on a continuous
/// scale over the values' range (the colour bar beside the cells), each
/// cell labelled with that number and, below it when it fits, the
/// worst-case estimate and the game upper bound.
pub fn plot_sweep(
    path: &Path,
    (format, size): (PlotFormat, PlotSize),
    title: &Title,
    points: &[SweepPoint],
) -> Result<(), OutputError> {
    #[cfg(feature = "plot")]
    return draw::sweep(path, (format, size), title, points);
    #[cfg(not(feature = "plot"))]
    {
        let _ = (format, size, title, points);
        Err(not_built(path))
    }
}

/// The error of drawing `path` in a build without the feature `plot`.
#[cfg(not(feature = "plot"))]
fn not_built(path: &Path) -> OutputError {
    OutputError::Plot {
        path: path.to_path_buf(),
        problem: "this build of posg-fsc draws no plots (cargo feature `plot`)".into(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn plot_sizes_read_width_x_height_within_bounds() {
        let size: PlotSize = "1200x700".parse().unwrap();
        assert_eq!((size.width, size.height), (1200, 700));
        assert_eq!("900X520".parse::<PlotSize>().unwrap(), PlotSize::default());
        for bad in [
            "1200",
            "x700",
            "1200x",
            "12.5x700",
            "100x100",
            "100000x700",
            "-5x700",
        ] {
            let error = bad.parse::<PlotSize>().unwrap_err();
            assert!(error.contains("WIDTHxHEIGHT"), "{bad}: {error}");
        }
    }
}
