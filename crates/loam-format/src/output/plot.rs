//! Line plots, drawn with plotters' SVG backend: the verification and convergence figures
//! of `cargo xtask`, and the plots of a run's logs (`loam plot`).
//!
//! Linear or logarithmic axes (labelled decades, like `1e-3`, on log axes), a title, axis
//! labels, a legend beside the plot, a distinct colour and marker per series, optional dashed
//! lines, and optional reference slopes for convergence plots: dashed grey lines of the given
//! slope through the last point of the first series, so the observed rate reads off against
//! them. Values that cannot be shown (NaN, infinities, non-positive values on a log axis)
//! are dropped before plotting, so the SVG never contains NaN coordinates.
//!
//! plotters is built without its `ttf` feature: text stays SVG `<text>` that the viewer sets in
//! its own sans-serif font, and plotters' width estimate is enough to lay the chart out. So
//! the build needs no font file and no system library.

use plotters::coord::ranged1d::{AsRangedCoord, Ranged, ValueFormatter};
use plotters::coord::CoordTranslate;
use plotters::coord::Shift;
use plotters::element::DashedPathElement;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use std::error::Error;
use std::path::Path;

/// One line of the plot.
#[derive(Debug, Clone, PartialEq)]
pub struct Series {
    /// Legend label.
    pub label: String,
    /// Data points `(x, y)`, drawn in order.
    pub points: Vec<(f64, f64)>,
    /// Draw the line dashed.
    pub dashed: bool,
}

impl Series {
    /// A solid series.
    pub fn new(label: impl Into<String>, points: Vec<(f64, f64)>) -> Self {
        Self { label: label.into(), points, dashed: false }
    }

    /// Makes the series dashed.
    pub fn dashed(mut self) -> Self {
        self.dashed = true;
        self
    }
}

/// A 2D line plot.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Plot {
    /// Title above the plot.
    pub title: String,
    /// Label under the x axis.
    pub x_label: String,
    /// Label left of the y axis.
    pub y_label: String,
    /// Logarithmic x axis.
    pub log_x: bool,
    /// Logarithmic y axis.
    pub log_y: bool,
    /// The lines.
    pub series: Vec<Series>,
    /// Reference slopes `(slope, label)` drawn as dashed grey lines through the last point
    /// of the first series, on log-log plots (where the slope is the convergence rate, e.g.
    /// `(2.0, "rate 2")`).
    pub reference_slopes: Vec<(f64, String)>,
}

/// Width of the chart (axes and plot area); the legend is added to its right.
const CHART_WIDTH: u32 = 580;
const MIN_HEIGHT: u32 = 480;
/// Vertical pitch of the legend rows, pixels.
const LEGEND_ROW: u32 = 20;
/// At most this many markers per series (energy histories have thousands of points).
const MAX_MARKERS: usize = 30;
const FONT: &str = "sans-serif";
/// plotters' font sizes are 1.24 times the SVG `font-size`: this is 12 px.
const TEXT_SIZE: f64 = 15.0;
const GREY: RGBColor = RGBColor(0x44, 0x44, 0x44);
/// The reference slopes alternate between two greys, so that two of them can be told apart.
const REFERENCE_GREYS: [RGBColor; 2] = [GREY, RGBColor(0xa0, 0xa0, 0xa0)];
const COLOURS: [RGBColor; 10] = [
    RGBColor(0x1f, 0x77, 0xb4),
    RGBColor(0xd6, 0x27, 0x28),
    RGBColor(0x2c, 0xa0, 0x2c),
    RGBColor(0xff, 0x7f, 0x0e),
    RGBColor(0x94, 0x67, 0xbd),
    RGBColor(0x8c, 0x56, 0x4b),
    RGBColor(0xe3, 0x77, 0xc2),
    RGBColor(0x17, 0xbe, 0xcf),
    RGBColor(0x7f, 0x7f, 0x7f),
    RGBColor(0xbc, 0xbd, 0x22),
];

/// A plotters axis of `f64` values, linear or logarithmic.
trait Axis: Ranged<ValueType = f64> + ValueFormatter<f64> {}
impl<T: Ranged<ValueType = f64> + ValueFormatter<f64>> Axis for T {}

/// The chart being drawn.
type Chart<'a, 'b, X, Y> = ChartContext<'a, SVGBackend<'b>, Cartesian2d<X, Y>>;

/// Values beyond this magnitude (or, on log axes, below its inverse) are skipped: the axis
/// range around them would overflow, and plotters' log-axis tick search never ends on an
/// infinite range.
const LIMIT: f64 = 1e300;

/// Converts a data value to axis units (`log10` on log axes); `None` when it cannot be shown.
fn to_axis(v: f64, log: bool) -> Option<f64> {
    if !v.is_finite() {
        None
    } else if log {
        (1.0 / LIMIT..=LIMIT).contains(&v).then(|| v.log10())
    } else {
        (v.abs() <= LIMIT).then_some(v)
    }
}

fn from_axis(t: f64, log: bool) -> f64 {
    if log {
        10f64.powf(t)
    } else {
        t
    }
}

/// The plotted range in axis units: whole decades on log axes (a little wider, so that
/// plotters' decade search, which steps by multiplying, still finds both end decades), the
/// data and a margin on linear ones.
fn axis_range(values: impl Iterator<Item = f64>, log: bool) -> (f64, f64) {
    let (min, max) = values.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| (lo.min(v), hi.max(v)));
    let (min, max) = if min > max { (0.0, 1.0) } else { (min, max) };
    if log {
        let (lo, hi) = (min.floor(), max.ceil());
        let (lo, hi) = if hi > lo { (lo, hi) } else { (lo - 1.0, hi + 1.0) };
        (lo - 0.02, hi + 0.02)
    } else {
        let pad = if max > min { 0.03 * (max - min) } else { 0.1 * min.abs().max(1.0) };
        (min - pad, max + pad)
    }
}

/// A tick label on a log axis: `1e-3` at a decade, `3e-3` between decades.
fn decade_label(v: &f64) -> String {
    let k = v.log10().round();
    if (v / 10f64.powf(k) - 1.0).abs() < 1e-6 {
        format!("1e{k}")
    } else {
        format!("{v:.0e}")
    }
}

/// Draws marker number `kind` (circle, square, triangle, diamond, inverted triangle, cross)
/// at `at`, in `area`'s coordinates.
fn draw_marker<CT: CoordTranslate>(
    area: &DrawingArea<SVGBackend, CT>,
    kind: usize,
    at: CT::From,
    colour: RGBColor,
) -> Result<(), Box<dyn Error>>
where
    CT::From: Clone + 'static,
{
    let fill = colour.filled();
    let base = EmptyElement::at(at);
    match kind % 6 {
        0 => area.draw(&(base + Circle::new((0, 0), 4, fill)))?,
        1 => area.draw(&(base + Rectangle::new([(-3, -3), (3, 3)], fill)))?,
        2 => area.draw(&(base + Polygon::new(vec![(0, -5), (4, 3), (-4, 3)], fill)))?,
        3 => area.draw(&(base + Polygon::new(vec![(0, -5), (5, 0), (0, 5), (-5, 0)], fill)))?,
        4 => area.draw(&(base + Polygon::new(vec![(0, 5), (4, -3), (-4, -3)], fill)))?,
        _ => area.draw(&(base + Cross::new((0, 0), 4, colour.stroke_width(2))))?,
    }
    Ok(())
}

/// The line of `slope` through `anchor` (axis units) over the plot ranges `x`, `y`: its
/// two ends where it enters and leaves that box, none where it misses it.
fn clipped_line(anchor: (f64, f64), slope: f64, x: (f64, f64), y: (f64, f64)) -> Vec<(f64, f64)> {
    let (xa, ya) = anchor;
    let at = |yy: f64| xa + (yy - ya) / slope;
    let (from, to) = if slope > 0.0 { (at(y.0), at(y.1)) } else { (at(y.1), at(y.0)) };
    let (lo, hi) = (x.0.max(from), x.1.min(to));
    // `lo >= hi` where the line misses the box, and false for NaN ends too.
    if lo.partial_cmp(&hi) != Some(std::cmp::Ordering::Less) {
        return Vec::new();
    }
    vec![(lo, ya + slope * (lo - xa)), (hi, ya + slope * (hi - xa))]
}

/// A line as drawn: its points in axis units, label, colour, dash, and marker (none for
/// the reference slopes).
struct Drawn<'a> {
    label: &'a str,
    points: Vec<(f64, f64)>,
    colour: RGBColor,
    dashed: bool,
    marker: Option<usize>,
}

/// The legend: a row per line with its stroke, marker and label.
fn legend(area: &DrawingArea<SVGBackend, Shift>, drawn: &[Drawn]) -> Result<(), Box<dyn Error>> {
    for (i, d) in drawn.iter().enumerate() {
        let y = 50 + (LEGEND_ROW as usize * i) as i32;
        let line = [(5, y), (35, y)];
        let style = d.colour.stroke_width(if d.marker.is_some() { 2 } else { 1 });
        if d.dashed {
            area.draw(&DashedPathElement::new(line, 7, 4, style))?;
        } else {
            area.draw(&PathElement::new(line, style))?;
        }
        if let Some(kind) = d.marker {
            draw_marker(area, kind, (20, y), d.colour)?;
        }
        let text = (FONT, TEXT_SIZE).into_font().color(&BLACK).pos(Pos::new(HPos::Left, VPos::Center));
        area.draw(&Text::new(d.label, (43, y), text))?;
    }
    Ok(())
}

impl Plot {
    /// An empty plot with linear axes.
    pub fn new(title: impl Into<String>, x_label: impl Into<String>, y_label: impl Into<String>) -> Self {
        Self { title: title.into(), x_label: x_label.into(), y_label: y_label.into(), ..Self::default() }
    }

    /// What is drawn: the visible points of each series in axis units, with its colour,
    /// whether it is dashed and has markers, and its label; then the reference slopes.
    fn drawn(&self) -> Vec<Drawn<'_>> {
        let mut drawn: Vec<Drawn> = self
            .series
            .iter()
            .enumerate()
            .map(|(i, s)| Drawn {
                label: &s.label,
                points: s
                    .points
                    .iter()
                    .filter_map(|&(x, y)| Some((to_axis(x, self.log_x)?, to_axis(y, self.log_y)?)))
                    .collect(),
                colour: COLOURS[i % COLOURS.len()],
                dashed: s.dashed,
                marker: Some(i),
            })
            .collect();
        let anchor = drawn.first().and_then(|d| d.points.last().copied());
        let x = axis_range(drawn.iter().flat_map(|d| d.points.iter().map(|p| p.0)), self.log_x);
        let y = axis_range(drawn.iter().flat_map(|d| d.points.iter().map(|p| p.1)), self.log_y);
        if let (Some(anchor), true) = (anchor, self.log_x && self.log_y) {
            let slopes = self.reference_slopes.iter().filter(|(s, _)| s.is_finite() && *s != 0.0);
            for (k, (slope, label)) in slopes.enumerate() {
                let points = clipped_line(anchor, *slope, x, y);
                drawn.push(Drawn { label, points, colour: REFERENCE_GREYS[k % 2], dashed: true, marker: None });
            }
        }
        drawn
    }

    /// Renders the plot as a standalone SVG document.
    pub fn to_svg(&self) -> Result<String, Box<dyn Error>> {
        let mut svg = String::new();
        self.render(&mut svg)?;
        Ok(svg)
    }

    fn render(&self, svg: &mut String) -> Result<(), Box<dyn Error>> {
        let drawn = self.drawn();
        let longest = drawn.iter().map(|d| d.label.chars().count()).max().unwrap_or(0);
        // About 6.5 px per character of 12 px sans-serif, and the line and marker before it.
        let legend_width = 60 + (6.5 * longest as f64) as u32;
        let height = MIN_HEIGHT.max(60 + LEGEND_ROW * drawn.len() as u32);
        let root = SVGBackend::with_string(svg, (CHART_WIDTH + legend_width, height)).into_drawing_area();
        root.fill(&WHITE)?;
        let (chart_area, legend_area) = root.split_horizontally(CHART_WIDTH);
        // The axes span the data; reference lines are clipped to them.
        let data = &drawn[..self.series.len()];
        let x = axis_range(data.iter().flat_map(|d| d.points.iter().map(|p| p.0)), self.log_x);
        let y = axis_range(data.iter().flat_map(|d| d.points.iter().map(|p| p.1)), self.log_y);
        let (xr, yr) = (
            from_axis(x.0, self.log_x)..from_axis(x.1, self.log_x),
            from_axis(y.0, self.log_y)..from_axis(y.1, self.log_y),
        );
        match (self.log_x, self.log_y) {
            (false, false) => self.chart(&chart_area, &drawn, (x, y), xr, yr)?,
            (true, false) => self.chart(&chart_area, &drawn, (x, y), xr.log_scale(), yr)?,
            (false, true) => self.chart(&chart_area, &drawn, (x, y), xr, yr.log_scale())?,
            (true, true) => self.chart(&chart_area, &drawn, (x, y), xr.log_scale(), yr.log_scale())?,
        }
        legend(&legend_area, &drawn)?;
        root.present()?;
        Ok(())
    }

    /// Draws axes and lines on `area`; `ranges` are the axes' ranges in axis units, `x` and
    /// `y` the same as plotters coordinates.
    fn chart<X, Y>(
        &self,
        area: &DrawingArea<SVGBackend, Shift>,
        drawn: &[Drawn],
        ranges: ((f64, f64), (f64, f64)),
        x: X,
        y: Y,
    ) -> Result<(), Box<dyn Error>>
    where
        X: AsRangedCoord<Value = f64>,
        Y: AsRangedCoord<Value = f64>,
        X::CoordDescType: Axis,
        Y::CoordDescType: Axis,
    {
        let mut chart = ChartBuilder::on(area)
            .caption(&self.title, (FONT, 1.25 * TEXT_SIZE))
            .margin(15)
            .x_label_area_size(45)
            .y_label_area_size(70)
            .build_cartesian_2d(x, y)?;
        self.axes(&mut chart, ranges)?;
        for d in drawn {
            let line = d.points.iter().map(|p| self.to_data(p));
            let style = d.colour.stroke_width(if d.marker.is_some() { 2 } else { 1 });
            if d.dashed {
                chart.draw_series(DashedLineSeries::new(line, 7, 4, style))?;
            } else {
                chart.draw_series(LineSeries::new(line, style))?;
            }
            if let Some(kind) = d.marker {
                let every = d.points.len().div_ceil(MAX_MARKERS).max(1);
                for p in d.points.iter().step_by(every) {
                    draw_marker(chart.plotting_area(), kind, self.to_data(p), d.colour)?;
                }
            }
        }
        Ok(())
    }

    /// A point in axis units back in data units.
    fn to_data(&self, &(x, y): &(f64, f64)) -> (f64, f64) {
        (from_axis(x, self.log_x), from_axis(y, self.log_y))
    }

    /// Grid, ticks, tick labels and axis labels.
    fn axes<X: Axis, Y: Axis>(
        &self,
        chart: &mut Chart<X, Y>,
        ranges: ((f64, f64), (f64, f64)),
    ) -> Result<(), Box<dyn Error>> {
        let mut mesh = chart.configure_mesh();
        mesh.x_desc(&self.x_label)
            .y_desc(&self.y_label)
            .label_style((FONT, TEXT_SIZE))
            .axis_desc_style((FONT, TEXT_SIZE))
            .bold_line_style(RGBColor(0xdd, 0xdd, 0xdd))
            .light_line_style(RGBColor(0xf2, 0xf2, 0xf2));
        // On log axes: a label at every decade (one in n when there are many), light lines at
        // 2..9 times each. On linear axes: the grid at the labels only.
        let decades = |(lo, hi): (f64, f64)| ((hi - lo).round() as usize + 1).min(11);
        if self.log_x {
            mesh.x_labels(decades(ranges.0)).x_label_formatter(&decade_label);
        } else {
            mesh.x_max_light_lines(0);
        }
        if self.log_y {
            mesh.y_labels(decades(ranges.1)).y_label_formatter(&decade_label);
        } else {
            mesh.y_max_light_lines(0);
        }
        mesh.draw()?;
        Ok(())
    }

    /// Writes the SVG to `path`, creating its parent folder if needed.
    pub fn write(&self, path: &Path) -> std::io::Result<()> {
        if let Some(parent) = path.parent() {
            if !parent.as_os_str().is_empty() {
                std::fs::create_dir_all(parent)?;
            }
        }
        let svg = self.to_svg().map_err(|e| std::io::Error::other(e.to_string()))?;
        std::fs::write(path, svg)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn convergence_plot() -> Plot {
        let h = [0.5, 0.25, 0.125, 0.0625];
        Plot {
            title: "Convergence <L2>".into(),
            x_label: "h".into(),
            y_label: "error".into(),
            log_x: true,
            log_y: true,
            series: vec![
                Series::new("u", h.iter().map(|&h| (h, 0.3 * h * h)).collect()),
                Series::new("p", h.iter().map(|&h| (h, 0.1 * h)).collect()).dashed(),
                Series::new("bad", vec![(0.0, 1.0), (-1.0, 2.0), (0.1, f64::NAN), (0.2, 0.0)]),
            ],
            reference_slopes: vec![(2.0, "rate 2".into()), (1.0, "rate 1".into())],
        }
    }

    /// The SVG of `plot`, checked to hold no NaN or infinite coordinate.
    fn finite_svg(plot: &Plot) -> String {
        let svg = plot.to_svg().unwrap();
        assert!(svg.starts_with("<svg") && svg.trim_end().ends_with("</svg>"));
        assert!(!svg.contains("NaN") && !svg.contains("inf"), "{svg}");
        svg
    }

    #[test]
    fn title_legend_and_reference_slopes() {
        let svg = finite_svg(&convergence_plot());
        assert!(svg.contains("Convergence &lt;L2&gt;"));
        for text in ["u", "p", "bad", "h", "error", "rate 2", "rate 1"] {
            assert!(svg.contains(&format!("\n{text}\n</text>")), "missing {text}");
        }
        // "u" solid: one polyline in the chart and one in the legend; "p" dashed: one per dash.
        assert_eq!(svg.matches("stroke=\"#1F77B4\" stroke-width=\"2\" points").count(), 1 + 1);
        assert!(svg.matches("stroke=\"#D62728\" stroke-width=\"2\" points").count() > 3);
    }

    /// Each reference slope is drawn, in its own grey, through the first series' finest
    /// point, and a steep one that leaves the plot is clipped to it rather than dropped.
    #[test]
    fn reference_slopes_are_drawn_and_clipped() {
        let mut plot = convergence_plot();
        let drawn_in =
            |svg: &str, grey: &str| svg.matches(&format!("stroke=\"{grey}\" stroke-width=\"1\" points")).count();
        let svg = finite_svg(&plot);
        // A dashed line is many short polylines (its legend row of 30 px three of them).
        assert!(drawn_in(&svg, "#444444") > 6 && drawn_in(&svg, "#A0A0A0") > 6, "{svg}");
        plot.reference_slopes = vec![(6.0, "steep".into())];
        let svg = finite_svg(&plot);
        assert!(drawn_in(&svg, "#444444") > 6, "the steep slope was dropped");
    }

    #[test]
    fn no_nan_or_inf_text() {
        let mut p = convergence_plot();
        finite_svg(&p);
        // Linear axes with NaN/inf values, and a plot with no usable data.
        p.log_x = false;
        p.log_y = false;
        p.series.push(Series::new("huge", vec![(f64::INFINITY, 1.0), (1.0, f64::NEG_INFINITY), (f64::MAX, 1.0)]));
        finite_svg(&p);
        p.log_x = true;
        p.log_y = true;
        finite_svg(&p);
        let empty = Plot {
            log_x: true,
            log_y: true,
            series: vec![Series::new("none", vec![(-1.0, -1.0)])],
            reference_slopes: vec![(2.0, "r".into())],
            ..Plot::default()
        };
        finite_svg(&empty);
        // Constant data on linear axes.
        finite_svg(&Plot { series: vec![Series::new("c", vec![(1.0, 5.0), (1.0, 5.0)])], ..Plot::default() });
    }

    #[test]
    fn log_ticks_at_decades() {
        let (lo, hi) = axis_range([2e-3f64.log10(), 50f64.log10()].into_iter(), true);
        assert_eq!((lo.round(), hi.round()), (-3.0, 2.0));
        let svg = finite_svg(&Plot {
            log_x: true,
            log_y: true,
            series: vec![Series::new("s", vec![(2e-3, 1.0), (50.0, 10.0)])],
            ..Plot::default()
        });
        for label in ["1e-3", "1e-2", "1e-1", "1e0", "1e1", "1e2"] {
            assert!(svg.contains(&format!("\n{label}\n</text>")), "missing {label}");
        }
        // A single value still spans decades.
        let (lo, hi) = axis_range(std::iter::once(0.0), true);
        assert!(hi - lo > 1.0);
        assert_eq!(decade_label(&1e-7), "1e-7");
        assert_eq!(decade_label(&1.0), "1e0");
        assert_eq!(decade_label(&3e4), "3e4");
    }

    #[test]
    fn write_creates_file() {
        let dir = std::env::temp_dir().join(format!("loam-svg-test-{}", std::process::id()));
        let path = dir.join("sub").join("plot.svg");
        convergence_plot().write(&path).unwrap();
        let text = std::fs::read_to_string(&path).unwrap();
        assert!(text.contains("<polyline"));
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
