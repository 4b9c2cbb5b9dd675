//! SVG plots with plotters: [`CurvePlot`] (`curve.svg`) and [`plot_sweep`]
//! (`sweep.svg`), sized and labelled for a paper: a two-line title, integer
//! ticks where the axis counts something, the legend beside the data.

use std::path::{Path, PathBuf};

use std::ops::Range;

use plotters::coord::Shift;
use plotters::coord::ranged1d::{DefaultFormatting, KeyPointHint, Ranged};
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use crate::optimise::{IterationRecord, ObserverError};

/// Width and height of every plot, in pixels.
const SIZE: (u32, u32) = (900, 520);
/// Width of the legend column right of the data.
const LEGEND_WIDTH: u32 = 210;
/// Height of the two title lines.
const TITLE_HEIGHT: u32 = 56;
/// Lines with at most this many points also get a marker per point.
const MAX_MARKED_POINTS: usize = 200;
const FONT: &str = "sans-serif";
/// The value at the last iterate (thin, light).
const VALUE_COLOUR: RGBColor = RGBColor(120, 120, 120);
/// The worst-case estimate (thick, dark).
const ESTIMATE_COLOUR: RGBColor = RGBColor(31, 83, 180);
/// The certified band and its edges.
const LOWER_COLOUR: RGBColor = RGBColor(26, 130, 60);
const UPPER_COLOUR: RGBColor = RGBColor(190, 50, 40);
const BAND_COLOUR: RGBColor = RGBColor(120, 170, 120);

/// A plot's title: the first line (e.g. game and formula) and the second
/// (sizes, structure).
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct Title {
    /// The first, larger line.
    pub main: String,
    /// The second, smaller line (may be empty).
    pub detail: String,
}

/// Draws `curve.svg` from one start's records: the shaded band
/// `[certified lower bound, game upper bound]` at the best-response checks
/// (where computed), its two edges, and over it the value
/// `V(phi_def(t), phi_adv)` and the worst-case estimate, against the
/// iteration (integer ticks); optionally a second axis on top with the
/// seconds elapsed at those iterations.
pub struct CurvePlot {
    path: PathBuf,
    title: Title,
    seconds_axis: bool,
}

impl CurvePlot {
    /// A plot to be written to `path` with `title`, without a seconds axis.
    pub fn new(path: &Path, title: Title) -> Self {
        Self {
            path: path.to_path_buf(),
            title,
            seconds_axis: false,
        }
    }

    /// Whether to draw the top axis with the seconds elapsed.
    pub fn with_seconds_axis(mut self, seconds_axis: bool) -> Self {
        self.seconds_axis = seconds_axis;
        self
    }
}

impl CurvePlot {
    /// Draws `records` (one start's, in iteration order) to the plot's file.
    pub fn draw(&self, records: &[IterationRecord]) -> Result<(), ObserverError> {
        draw_curve(&self.path, &self.title, records, self.seconds_axis)
    }
}

/// One legend entry: its text and how its sample is drawn.
struct LegendEntry {
    text: String,
    colour: RGBColor,
    kind: LegendKind,
}

enum LegendKind {
    Line(u32),
    Band,
    Cell,
}

fn draw_curve(
    path: &Path,
    title: &Title,
    records: &[IterationRecord],
    seconds_axis: bool,
) -> Result<(), ObserverError> {
    let at = |pick: fn(&IterationRecord) -> Option<f64>| -> Vec<(f64, f64)> {
        records
            .iter()
            .filter_map(|r| pick(r).map(|y| (r.iteration as f64, y)))
            .collect()
    };
    let values = at(|r| Some(r.value));
    let estimates = at(|r| r.worst_case);
    let lower = at(|r| r.certified_lower);
    let upper = at(|r| r.upper_bound);
    let x_max = records.last().map_or(1.0, |r| r.iteration.max(1) as f64);
    let all = values.iter().chain(&estimates).chain(&lower).chain(&upper);
    let (y_min, y_max) = padded_range(all.map(|&(_, y)| y));
    let root = SVGBackend::new(path, SIZE).into_drawing_area();
    root.fill(&WHITE)?;
    let (plot_area, legend_area) = frame(&root, title)?;
    let seconds_axis = seconds_axis && records.len() > 1;
    let mut chart = ChartBuilder::on(&plot_area)
        .margin(10)
        .margin_top(if seconds_axis { 48 } else { 10 })
        .x_label_area_size(45)
        .y_label_area_size(65)
        .build_cartesian_2d(Ticked::new(0.0..x_max, integer_ticks(x_max)), y_min..y_max)?;
    chart
        .configure_mesh()
        .x_desc("iteration")
        .y_desc("probability of phi")
        .x_label_formatter(&|x| format!("{x:.0}"))
        .y_label_formatter(&|y| format!("{y:.2}"))
        .label_style((FONT, 15))
        .axis_desc_style((FONT, 17))
        .light_line_style(WHITE.mix(0.0))
        .bold_line_style(BLACK.mix(0.08))
        .draw()?;
    let mut legend = Vec::new();
    if !lower.is_empty() && lower.len() == upper.len() {
        let band: Vec<(f64, f64)> = lower.iter().chain(upper.iter().rev()).copied().collect();
        chart.draw_series(std::iter::once(Polygon::new(
            band,
            BAND_COLOUR.mix(0.25).filled(),
        )))?;
        legend.push(entry("certified bracket", BAND_COLOUR, LegendKind::Band));
    }
    let lines = [
        (&lower, "certified lower bound", LOWER_COLOUR, 1),
        (&upper, "game upper bound", UPPER_COLOUR, 1),
        (&values, "value (last iterate)", VALUE_COLOUR, 1),
        (&estimates, "worst-case estimate", ESTIMATE_COLOUR, 3),
    ];
    for (line, name, colour, width) in lines {
        if line.is_empty() {
            continue;
        }
        chart.draw_series(LineSeries::new(
            line.iter().copied(),
            colour.stroke_width(width),
        ))?;
        if width > 1 && line.len() <= MAX_MARKED_POINTS {
            chart.draw_series(line.iter().map(|&p| Circle::new(p, 3, colour.filled())))?;
        }
        legend.push(entry(name, colour, LegendKind::Line(width)));
    }
    if seconds_axis {
        let top = |x: f64| chart.backend_coord(&(x, y_max));
        let (left, right) = (top(0.0), top(x_max));
        let style = TextStyle::from((FONT, 13).into_font()).pos(anchor(HPos::Center, VPos::Bottom));
        root.draw(&PathElement::new(vec![left, right], BLACK.stroke_width(1)))?;
        for (position, label) in seconds_ticks(records) {
            let (x, y) = top(position);
            root.draw(&PathElement::new(
                vec![(x, y), (x, y - 5)],
                BLACK.stroke_width(1),
            ))?;
            root.draw(&Text::new(label, (x, y - 7), style.clone()))?;
        }
        let desc = TextStyle::from((FONT, 15).into_font()).pos(anchor(HPos::Center, VPos::Bottom));
        root.draw(&Text::new(
            "seconds",
            ((left.0 + right.0) / 2, left.1 - 22),
            desc,
        ))?;
    }
    draw_legend(&legend_area, &legend)?;
    root.present()?;
    Ok(())
}

/// A linear axis over `range` with ticks exactly at `ticks` (plotters
/// picks its own otherwise).
struct Ticked {
    range: Range<f64>,
    ticks: Vec<f64>,
}

impl Ticked {
    fn new(range: Range<f64>, ticks: Vec<f64>) -> Self {
        Self { range, ticks }
    }
}

impl Ranged for Ticked {
    type FormatOption = DefaultFormatting;
    type ValueType = f64;

    fn map(&self, value: &f64, limit: (i32, i32)) -> i32 {
        let share = (value - self.range.start) / (self.range.end - self.range.start);
        limit.0 + (share * f64::from(limit.1 - limit.0)).round() as i32
    }

    fn key_points<Hint: KeyPointHint>(&self, hint: Hint) -> Vec<f64> {
        if hint.weight().allow_light_points() {
            Vec::new()
        } else {
            self.ticks.clone()
        }
    }

    fn range(&self) -> Range<f64> {
        self.range.clone()
    }
}

fn entry(text: &str, colour: RGBColor, kind: LegendKind) -> LegendEntry {
    LegendEntry {
        text: text.to_string(),
        colour,
        kind,
    }
}

/// A plot area and the legend column beside it.
type Areas<'b> = (
    DrawingArea<SVGBackend<'b>, Shift>,
    DrawingArea<SVGBackend<'b>, Shift>,
);

/// Draws the title on top of `root` and returns the plot area and the
/// legend column right of it.
fn frame<'b>(
    root: &DrawingArea<SVGBackend<'b>, Shift>,
    title: &Title,
) -> Result<Areas<'b>, ObserverError> {
    let (head, body) = root.split_vertically(TITLE_HEIGHT);
    let centre = (SIZE.0 / 2) as i32;
    let style =
        |size: u32| TextStyle::from((FONT, size).into_font()).pos(anchor(HPos::Center, VPos::Top));
    head.draw(&Text::new(title.main.clone(), (centre, 8), style(20)))?;
    if !title.detail.is_empty() {
        head.draw(&Text::new(title.detail.clone(), (centre, 34), style(15)))?;
    }
    Ok(body.split_horizontally(SIZE.0 - LEGEND_WIDTH))
}

/// The legend: one sample and text per entry, from the top of `area`.
fn draw_legend(
    area: &DrawingArea<SVGBackend, Shift>,
    entries: &[LegendEntry],
) -> Result<(), ObserverError> {
    for (i, entry) in entries.iter().enumerate() {
        let y = 30 + 26 * i as i32;
        match entry.kind {
            LegendKind::Line(width) => area.draw(&PathElement::new(
                vec![(8, y), (38, y)],
                entry.colour.stroke_width(width),
            ))?,
            LegendKind::Band => area.draw(&Rectangle::new(
                [(8, y - 7), (38, y + 7)],
                entry.colour.mix(0.25).filled(),
            ))?,
            LegendKind::Cell => area.draw(&Rectangle::new(
                [(8, y - 7), (38, y + 7)],
                entry.colour.filled(),
            ))?,
        }
        area.draw(&Text::new(
            entry.text.clone(),
            (46, y - 8),
            (FONT, 14).into_font(),
        ))?;
    }
    Ok(())
}

/// `[min, max]` of the values widened by 5% (at least 0.001 on each side);
/// `[0, 1]` without values.
fn padded_range(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (lo, hi) = values.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), y| {
        (lo.min(y), hi.max(y))
    });
    if !lo.is_finite() {
        return (0.0, 1.0);
    }
    let margin = ((hi - lo) * 0.05).max(1e-3);
    (lo - margin, hi + margin)
}

/// About eight ticks at multiples of 1, 2 or 5 times a power of ten, all
/// whole numbers, from 0 to `max`.
fn integer_ticks(max: f64) -> Vec<f64> {
    let step = nice_step(max / 8.0).max(1.0);
    let count = (max / step).floor() as usize;
    (0..=count).map(|k| k as f64 * step).collect()
}

/// The smallest of 1, 2, 5 times a power of ten that is at least `raw`.
fn nice_step(raw: f64) -> f64 {
    if raw <= 0.0 || !raw.is_finite() {
        return 1.0;
    }
    let power = 10f64.powf(raw.log10().floor());
    [1.0, 2.0, 5.0, 10.0]
        .into_iter()
        .map(|m| m * power)
        .find(|&s| s >= raw)
        .unwrap_or(10.0 * power)
}

/// The top axis: for round numbers of seconds, the (fractional) iteration
/// at which that much time had elapsed, and the label to show there.
fn seconds_ticks(records: &[IterationRecord]) -> Vec<(f64, String)> {
    let total = records.last().map_or(0.0, |r| r.seconds);
    let step = nice_step(total / 6.0);
    let decimals = if step >= 1.0 {
        0
    } else {
        (-step.log10().floor()) as usize
    };
    let mut ticks = Vec::new();
    let mut k = 1.0;
    while k * step <= total {
        let target = k * step;
        if let Some(w) = records.windows(2).find(|w| w[1].seconds >= target) {
            let (a, b) = (&w[0], &w[1]);
            let share = if b.seconds > a.seconds {
                ((target - a.seconds) / (b.seconds - a.seconds)).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let position = a.iteration as f64 + share * (b.iteration as f64 - a.iteration as f64);
            ticks.push((position, format!("{target:.decimals$}")));
        }
        k += 1.0;
    }
    ticks
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

/// Draws `sweep.svg`: a heatmap with one cell per (defender size, adversary
/// size), coloured by the certified lower bound (or, without certification,
/// by the worst-case estimate) on a white-to-blue scale from 0 to 1, and
/// labelled with that number and, below it, the worst-case estimate and the
/// game upper bound. The colour scale is beside the cells.
pub fn plot_sweep(path: &Path, title: &Title, points: &[SweepPoint]) -> Result<(), ObserverError> {
    let sizes = |pick: fn(&SweepPoint) -> usize| {
        let mut v: Vec<usize> = points.iter().map(pick).collect();
        v.sort_unstable();
        v.dedup();
        v
    };
    let (defender_sizes, adversary_sizes) =
        (sizes(|p| p.defender_nodes), sizes(|p| p.adversary_nodes));
    let certified = points.iter().all(|p| p.bracket.is_some());
    let root = SVGBackend::new(path, SIZE).into_drawing_area();
    root.fill(&WHITE)?;
    let (plot_area, legend_area) = frame(&root, title)?;
    let mut chart = ChartBuilder::on(&plot_area)
        .margin(10)
        .x_label_area_size(45)
        .y_label_area_size(65)
        .build_cartesian_2d(cells(defender_sizes.len()), cells(adversary_sizes.len()))?;
    let label = |sizes: &[usize], v: &f64| {
        sizes
            .get(v.floor() as usize)
            .map_or(String::new(), |s| s.to_string())
    };
    chart
        .configure_mesh()
        .disable_mesh()
        .x_desc("defender nodes")
        .y_desc("adversary nodes")
        .x_label_formatter(&|v| label(&defender_sizes, v))
        .y_label_formatter(&|v| label(&adversary_sizes, v))
        .label_style((FONT, 15))
        .axis_desc_style((FONT, 17))
        .draw()?;
    for p in points {
        let i = defender_sizes.binary_search(&p.defender_nodes).unwrap_or(0);
        let j = adversary_sizes
            .binary_search(&p.adversary_nodes)
            .unwrap_or(0);
        let shown = p.bracket.map_or(p.worst_case, |b| b.0);
        let (i, j) = (i as f64, j as f64);
        let cell = [(i, j), (i + 1.0, j + 1.0)];
        chart.draw_series(std::iter::once(Rectangle::new(cell, heat(shown).filled())))?;
        chart.draw_series(std::iter::once(Rectangle::new(cell, WHITE.stroke_width(2))))?;
        let ink = if shown > 0.6 { WHITE } else { BLACK };
        let centre = (i + 0.5, j + 0.5);
        let big = TextStyle::from((FONT, 22).into_font())
            .color(&ink)
            .pos(centred());
        chart
            .plotting_area()
            .draw(&Text::new(format!("{shown:.3}"), centre, big))?;
        let small_text = match p.bracket {
            Some((_, upper)) => format!("est. {:.3}, ub {:.3}", p.worst_case, upper),
            None => String::new(),
        };
        if !small_text.is_empty() {
            let (x, y) = chart.backend_coord(&centre);
            let small = TextStyle::from((FONT, 13).into_font())
                .color(&ink)
                .pos(centred());
            root.draw(&Text::new(small_text, (x, y + 22), small))?;
        }
    }
    let measured = if certified {
        "cell: certified lower bound"
    } else {
        "cell: worst-case estimate"
    };
    let mut legend = vec![entry(measured, WHITE, LegendKind::Cell)];
    if certified {
        legend.push(entry("est.: worst-case estimate", WHITE, LegendKind::Cell));
        legend.push(entry("ub: game upper bound", WHITE, LegendKind::Cell));
    }
    for level in [0.0, 0.25, 0.5, 0.75, 1.0] {
        legend.push(entry(&format!("{level:.2}"), heat(level), LegendKind::Cell));
    }
    draw_legend(&legend_area, &legend)?;
    root.present()?;
    Ok(())
}

/// An axis of `n` unit cells with a tick in the middle of each.
fn cells(n: usize) -> Ticked {
    Ticked::new(0.0..n as f64, (0..n).map(|i| i as f64 + 0.5).collect())
}

/// Text anchored at its centre.
fn centred() -> Pos {
    anchor(HPos::Center, VPos::Center)
}

fn anchor(horizontal: HPos, vertical: VPos) -> Pos {
    Pos::new(horizontal, vertical)
}

/// White (0) to dark blue (1).
fn heat(value: f64) -> RGBColor {
    let t = value.clamp(0.0, 1.0);
    let mix = |from: f64, to: f64| (from + (to - from) * t).round() as u8;
    RGBColor(mix(247.0, 8.0), mix(251.0, 48.0), mix(255.0, 107.0))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn integer_ticks_are_whole_numbers_about_eight_of_them() {
        assert_eq!(integer_ticks(3.0), vec![0.0, 1.0, 2.0, 3.0]);
        assert_eq!(integer_ticks(199.0), vec![0.0, 50.0, 100.0, 150.0]);
        assert_eq!(integer_ticks(20.0), vec![0.0, 5.0, 10.0, 15.0, 20.0]);
    }

    fn record(iteration: usize, seconds: f64) -> IterationRecord {
        IterationRecord {
            start: 0,
            iteration,
            seconds,
            value: 0.5,
            defender_gradient_norm: 0.0,
            adversary_gradient_norm: 0.0,
            defender_step: 0.0,
            adversary_step: 0.0,
            worst_case: None,
            certified_lower: None,
            upper_bound: None,
            logit_bound: 4.0,
        }
    }

    #[test]
    fn seconds_ticks_sit_where_that_much_time_had_elapsed() {
        // 0.1 s per iteration for 10 iterations, then 1 s per iteration.
        let records: Vec<IterationRecord> = (0..=20)
            .map(|t| {
                record(
                    t,
                    if t <= 10 {
                        0.1 * t as f64
                    } else {
                        1.0 + (t - 10) as f64
                    },
                )
            })
            .collect();
        let ticks = seconds_ticks(&records);
        assert_eq!(ticks[0].1, "2");
        assert!((ticks[0].0 - 11.0).abs() < 1e-9, "{ticks:?}");
        assert_eq!(ticks.last().unwrap().1, "10");
        assert!((ticks.last().unwrap().0 - 19.0).abs() < 1e-9);
    }

    #[test]
    fn nice_steps_are_one_two_or_five_times_a_power_of_ten() {
        assert_eq!(nice_step(0.3), 0.5);
        assert_eq!(nice_step(24.9), 50.0);
        assert_eq!(nice_step(20.0), 20.0);
        assert_eq!(nice_step(0.0), 1.0);
    }
}
