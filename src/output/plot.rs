//! SVG line plots with plotters.

use std::path::{Path, PathBuf};

use plotters::prelude::*;

use crate::optimise::{IterationRecord, Observer, ObserverError};

const SIZE: (u32, u32) = (800, 500);
/// Lines with at most this many points also get a marker per point.
const MAX_MARKED_POINTS: usize = 200;
const PALETTE: [RGBColor; 6] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(255, 127, 14),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
];

/// Collects the records and, at the end, draws `curve.svg`: the value
/// `V(phi_def(t), phi_adv)` as a line and each worst-case estimate as a
/// point with a line through them, against the iteration.
pub struct CurvePlot {
    path: PathBuf,
    title: String,
    records: Vec<IterationRecord>,
}

impl CurvePlot {
    /// A plot to be written to `path` with `title`.
    pub fn new(path: &Path, title: &str) -> Self {
        Self {
            path: path.to_path_buf(),
            title: title.to_string(),
            records: Vec::new(),
        }
    }
}

impl Observer for CurvePlot {
    fn observe(&mut self, record: &IterationRecord) {
        self.records.push(*record);
    }

    fn finish(&mut self) -> Result<(), ObserverError> {
        let values: Vec<(f64, f64)> = self
            .records
            .iter()
            .map(|r| (r.iteration as f64, r.value))
            .collect();
        let checked = |pick: fn(&IterationRecord) -> Option<f64>| -> Vec<(f64, f64)> {
            self.records
                .iter()
                .filter_map(|r| pick(r).map(|y| (r.iteration as f64, y)))
                .collect()
        };
        let mut series = vec![
            ("value", values),
            ("worst-case estimate", checked(|r| r.worst_case)),
        ];
        let lower = checked(|r| r.certified_lower);
        if !lower.is_empty() {
            series.push(("certified lower bound", lower));
            series.push(("game upper bound", checked(|r| r.upper_bound)));
        }
        draw_lines(
            &self.path,
            &self.title,
            "iteration",
            "probability of phi",
            &series,
        )
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

/// Draws `sweep.svg`: the worst-case estimate against the defender's size,
/// one line per adversary size, and, where computed, the certified lower
/// bound and the game upper bound of each adversary size.
pub fn plot_sweep(path: &Path, title: &str, points: &[SweepPoint]) -> Result<(), ObserverError> {
    let mut sizes: Vec<usize> = points.iter().map(|p| p.adversary_nodes).collect();
    sizes.sort_unstable();
    sizes.dedup();
    let line_of = |m: usize, y: &dyn Fn(&SweepPoint) -> Option<f64>| {
        let mut line: Vec<(f64, f64)> = points
            .iter()
            .filter(|p| p.adversary_nodes == m)
            .filter_map(|p| y(p).map(|y| (p.defender_nodes as f64, y)))
            .collect();
        line.sort_by(|a, b| a.0.total_cmp(&b.0));
        line
    };
    let mut series: Vec<(String, Vec<(f64, f64)>)> = Vec::new();
    for &m in &sizes {
        series.push((
            format!("worst-case estimate, adversary nodes = {m}"),
            line_of(m, &|p| Some(p.worst_case)),
        ));
        let lower = line_of(m, &|p| p.bracket.map(|b| b.0));
        if !lower.is_empty() {
            series.push((
                format!("certified lower bound, adversary nodes = {m}"),
                lower,
            ));
            series.push((
                format!("game upper bound, adversary nodes = {m}"),
                line_of(m, &|p| p.bracket.map(|b| b.1)),
            ));
        }
    }
    draw_lines(path, title, "defender nodes", "probability of phi", &series)
}

fn draw_lines<S: AsRef<str>>(
    path: &Path,
    title: &str,
    x_label: &str,
    y_label: &str,
    series: &[(S, Vec<(f64, f64)>)],
) -> Result<(), ObserverError> {
    let all = series.iter().flat_map(|(_, line)| line.iter());
    let (x_max, y_min, y_max) = all.fold(
        (1.0f64, f64::INFINITY, f64::NEG_INFINITY),
        |(x, lo, hi), &(px, py)| (x.max(px), lo.min(py), hi.max(py)),
    );
    let (y_min, y_max) = if y_min.is_finite() {
        (y_min, y_max)
    } else {
        (0.0, 1.0)
    };
    let margin = ((y_max - y_min) * 0.05).max(1e-3);
    let root = SVGBackend::new(path, SIZE).into_drawing_area();
    root.fill(&WHITE)?;
    let mut chart = ChartBuilder::on(&root)
        .caption(title, ("sans-serif", 20))
        .margin(15)
        .x_label_area_size(40)
        .y_label_area_size(60)
        .build_cartesian_2d(0.0..x_max, (y_min - margin)..(y_max + margin))?;
    chart
        .configure_mesh()
        .x_desc(x_label)
        .y_desc(y_label)
        .draw()?;
    for (i, (name, line)) in series.iter().enumerate() {
        let color = PALETTE[i % PALETTE.len()];
        chart
            .draw_series(LineSeries::new(line.iter().copied(), color.stroke_width(2)))?
            .label(name.as_ref())
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(2))
            });
        if line.len() <= MAX_MARKED_POINTS {
            chart.draw_series(line.iter().map(|&p| Circle::new(p, 3, color.filled())))?;
        }
    }
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .position(SeriesLabelPosition::LowerRight)
        .draw()?;
    root.present()?;
    Ok(())
}
