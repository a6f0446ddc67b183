//! A tiny dependency-free SVG line plot, for verification and convergence
//! figures.
//!
//! Linear or logarithmic axes (ticks at decades, labelled like `1e-3`, on log
//! axes; 1-2-5 "nice" ticks on linear axes), a legend, a distinct colour and
//! marker per series, optional dashed lines, and optional reference slope
//! triangles for convergence plots. Values that cannot be shown (NaN,
//! infinities, non-positive values on a log axis) are skipped, so the SVG
//! never contains NaN coordinates.

use loam::io::output::xml_escape;
use std::fmt::Write as _;
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
    /// Reference slopes `(slope, label)` drawn as small triangles under the
    /// data (in log-log plots the slope is the convergence rate, e.g.
    /// `(2.0, "rate 2")`).
    pub reference_slopes: Vec<(f64, String)>,
}

const WIDTH: f64 = 760.0;
const HEIGHT: f64 = 480.0;
const LEFT: f64 = 80.0;
const TOP: f64 = 40.0;
const RIGHT: f64 = 570.0;
const BOTTOM: f64 = 420.0;
const LEGEND_X: f64 = 585.0;
const MAX_MARKERS: usize = 30;

const COLOURS: [&str; 10] =
    ["#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#9467bd", "#8c564b", "#e377c2", "#17becf", "#7f7f7f", "#bcbd22"];

/// Values beyond this magnitude are skipped on linear axes (their spans
/// would overflow).
const LINEAR_LIMIT: f64 = 1e300;

/// Converts a data value to axis space (`log10` on log axes); `None` when it
/// cannot be shown.
fn to_axis(v: f64, log: bool) -> Option<f64> {
    if !v.is_finite() {
        None
    } else if log {
        (v > 0.0).then(|| v.log10())
    } else {
        (v.abs() <= LINEAR_LIMIT).then_some(v)
    }
}

/// An axis in axis space: `[lo, hi]`, major ticks with labels, minor ticks.
#[derive(Debug, Clone, PartialEq)]
struct Axis {
    lo: f64,
    hi: f64,
    ticks: Vec<(f64, String)>,
    minor: Vec<f64>,
}

impl Axis {
    fn new(values: impl Iterator<Item = f64>, log: bool) -> Self {
        let (mut min, mut max) = (f64::INFINITY, f64::NEG_INFINITY);
        for v in values {
            min = min.min(v);
            max = max.max(v);
        }
        if min > max {
            // No data: a default range.
            (min, max) = (0.0, 1.0);
        }
        if log {
            log_axis(min, max)
        } else {
            linear_axis(min, max)
        }
    }

    /// Fraction of the way from `lo` to `hi`.
    fn frac(&self, t: f64) -> f64 {
        (t - self.lo) / (self.hi - self.lo)
    }
}

/// Decade exponents spanning `[lo_t, hi_t]` (log10 values): the axis range
/// `(lo, hi)` in whole decades and the labelled decade exponents.
fn log_decades(lo_t: f64, hi_t: f64) -> (i32, i32, Vec<i32>) {
    let mut lo = lo_t.floor() as i32;
    let mut hi = hi_t.ceil() as i32;
    if hi <= lo {
        lo -= 1;
        hi += 1;
    }
    // At most ~10 labelled decades.
    let step = ((hi - lo) as f64 / 10.0).ceil().max(1.0) as i32;
    let ticks = (lo..=hi).filter(|k| k.rem_euclid(step) == 0).collect();
    (lo, hi, ticks)
}

fn log_axis(lo_t: f64, hi_t: f64) -> Axis {
    let (lo, hi, decades) = log_decades(lo_t, hi_t);
    let ticks = decades.iter().map(|&k| (k as f64, format!("1e{k}"))).collect();
    let mut minor = Vec::new();
    if hi - lo <= 6 {
        for k in lo..hi {
            for m in 2..=9 {
                minor.push(k as f64 + (m as f64).log10());
            }
        }
    }
    Axis { lo: lo as f64, hi: hi as f64, ticks, minor }
}

/// The 1-2-5 step nearest (geometrically) to `raw`.
fn nice_step(raw: f64) -> f64 {
    let mag = 10f64.powf(raw.log10().floor());
    let f = raw / mag;
    let nice = if f < 2f64.sqrt() {
        1.0
    } else if f < 10f64.sqrt() {
        2.0
    } else if f < 50f64.sqrt() {
        5.0
    } else {
        10.0
    };
    nice * mag
}

fn linear_axis(mut min: f64, mut max: f64) -> Axis {
    if max - min <= 0.0 {
        let pad = if min != 0.0 { min.abs() * 0.1 } else { 1.0 };
        min -= pad;
        max += pad;
    }
    let step = nice_step((max - min) / 5.0);
    let i_lo = (min / step).floor();
    let i_hi = (max / step).ceil();
    let (lo, hi) = (i_lo * step, i_hi * step);
    let max_abs = lo.abs().max(hi.abs());
    let ticks = (i_lo as i64..=i_hi as i64)
        .map(|i| {
            let v = i as f64 * step;
            (v, tick_label(if i == 0 { 0.0 } else { v }, step, max_abs))
        })
        .collect();
    Axis { lo, hi, ticks, minor: Vec::new() }
}

/// Label for a linear tick `v` on an axis with tick spacing `step` whose
/// largest magnitude is `max_abs`: just enough digits to tell ticks apart.
fn tick_label(v: f64, step: f64, max_abs: f64) -> String {
    if v == 0.0 {
        return "0".to_owned();
    }
    let step_mag = step.log10().floor() as i32;
    if !(1e-3..1e5).contains(&max_abs) {
        let digits = (max_abs.log10().floor() as i32 - step_mag).clamp(0, 12) as usize;
        let s = format!("{v:.digits$e}");
        // Drop trailing zeros of the mantissa: 2.50e6 -> 2.5e6, 2.0e6 -> 2e6.
        match s.split_once('e') {
            Some((mant, exp)) if mant.contains('.') => {
                let mant = mant.trim_end_matches('0').trim_end_matches('.');
                format!("{mant}e{exp}")
            }
            _ => s,
        }
    } else {
        let decimals = (-step_mag).max(0) as usize;
        format!("{v:.decimals$}")
    }
}

/// Pixel coordinate, or `None` if it would not be finite.
fn px(v: f64) -> Option<String> {
    v.is_finite().then(|| format!("{v:.2}"))
}

/// Draws marker number `kind` centred at `(x, y)`.
fn marker(out: &mut String, kind: usize, x: f64, y: f64, colour: &str) {
    let r = 3.5;
    let (Some(_), Some(_)) = (px(x), px(y)) else {
        return;
    };
    let poly = |pts: &[(f64, f64)]| {
        pts.iter().map(|(dx, dy)| format!("{:.2},{:.2}", x + dx, y + dy)).collect::<Vec<_>>().join(" ")
    };
    let _ = match kind % 6 {
        0 => writeln!(out, r#"<circle cx="{x:.2}" cy="{y:.2}" r="{r}" fill="{colour}"/>"#),
        1 => writeln!(
            out,
            r#"<rect x="{:.2}" y="{:.2}" width="{:.2}" height="{:.2}" fill="{colour}"/>"#,
            x - r,
            y - r,
            2.0 * r,
            2.0 * r
        ),
        2 => writeln!(
            out,
            r#"<polygon points="{}" fill="{colour}"/>"#,
            poly(&[(0.0, -1.2 * r), (1.1 * r, 0.9 * r), (-1.1 * r, 0.9 * r)])
        ),
        3 => writeln!(
            out,
            r#"<polygon points="{}" fill="{colour}"/>"#,
            poly(&[(0.0, -1.3 * r), (1.3 * r, 0.0), (0.0, 1.3 * r), (-1.3 * r, 0.0)])
        ),
        4 => writeln!(
            out,
            r#"<polygon points="{}" fill="{colour}"/>"#,
            poly(&[(0.0, 1.2 * r), (1.1 * r, -0.9 * r), (-1.1 * r, -0.9 * r)])
        ),
        _ => writeln!(
            out,
            r#"<path d="M{:.2},{:.2}L{:.2},{:.2}M{:.2},{:.2}L{:.2},{:.2}" stroke="{colour}" stroke-width="2"/>"#,
            x - r,
            y - r,
            x + r,
            y + r,
            x - r,
            y + r,
            x + r,
            y - r
        ),
    };
}

/// Points along the closed outline of a triangle, 8 per edge.
fn edge_samples(tri: &[(f64, f64); 3]) -> Vec<(f64, f64)> {
    let mut out = Vec::with_capacity(24);
    for k in 0..3 {
        let (a, b) = (tri[k], tri[(k + 1) % 3]);
        for m in 0..8 {
            let t = m as f64 / 8.0;
            out.push((a.0 + t * (b.0 - a.0), a.1 + t * (b.1 - a.1)));
        }
    }
    out
}

/// Distance from `p` to the nearest of the polylines (a single point counts
/// as a line); infinite if there are none.
fn distance_to_lines(p: (f64, f64), lines: &[Vec<(f64, f64)>]) -> f64 {
    let seg = |a: (f64, f64), b: (f64, f64)| {
        let (dx, dy) = (b.0 - a.0, b.1 - a.1);
        let len2 = dx * dx + dy * dy;
        let t = if len2 > 0.0 { (((p.0 - a.0) * dx + (p.1 - a.1) * dy) / len2).clamp(0.0, 1.0) } else { 0.0 };
        (p.0 - a.0 - t * dx).hypot(p.1 - a.1 - t * dy)
    };
    let mut d = f64::INFINITY;
    for line in lines {
        match line.len() {
            0 => {}
            1 => d = d.min(seg(line[0], line[0])),
            _ => {
                for w in line.windows(2) {
                    d = d.min(seg(w[0], w[1]));
                }
            }
        }
    }
    d
}

impl Plot {
    /// An empty plot with linear axes.
    pub fn new(title: impl Into<String>, x_label: impl Into<String>, y_label: impl Into<String>) -> Self {
        Self { title: title.into(), x_label: x_label.into(), y_label: y_label.into(), ..Self::default() }
    }

    /// The visible points of each series, in axis space.
    fn axis_points(&self) -> Vec<Vec<(f64, f64)>> {
        self.series
            .iter()
            .map(|s| {
                s.points.iter().filter_map(|&(x, y)| Some((to_axis(x, self.log_x)?, to_axis(y, self.log_y)?))).collect()
            })
            .collect()
    }

    /// Renders the plot as a standalone SVG document.
    pub fn to_svg(&self) -> String {
        let data = self.axis_points();
        let xa = Axis::new(data.iter().flatten().map(|p| p.0), self.log_x);
        let ya = Axis::new(data.iter().flatten().map(|p| p.1), self.log_y);
        let sx = |t: f64| LEFT + xa.frac(t) * (RIGHT - LEFT);
        let sy = |t: f64| BOTTOM - ya.frac(t) * (BOTTOM - TOP);

        let mut o = String::new();
        let _ = writeln!(
            o,
            r#"<svg xmlns="http://www.w3.org/2000/svg" width="{WIDTH}" height="{HEIGHT}" viewBox="0 0 {WIDTH} {HEIGHT}" font-family="sans-serif" font-size="12">"#
        );
        let _ = writeln!(o, r#"<rect x="0" y="0" width="{WIDTH}" height="{HEIGHT}" fill="white"/>"#);
        let _ = writeln!(
            o,
            r#"<defs><clipPath id="plot-area"><rect x="{}" y="{}" width="{}" height="{}"/></clipPath></defs>"#,
            LEFT - 5.0,
            TOP - 5.0,
            RIGHT - LEFT + 10.0,
            BOTTOM - TOP + 10.0
        );

        // Grid, ticks and tick labels.
        let _ = writeln!(o, r##"<g stroke="#dddddd" stroke-width="1">"##);
        for (t, _) in &xa.ticks {
            let x = sx(*t);
            let _ = writeln!(o, r#"<line x1="{x:.2}" y1="{TOP}" x2="{x:.2}" y2="{BOTTOM}"/>"#);
        }
        for (t, _) in &ya.ticks {
            let y = sy(*t);
            let _ = writeln!(o, r#"<line x1="{LEFT}" y1="{y:.2}" x2="{RIGHT}" y2="{y:.2}"/>"#);
        }
        let _ = writeln!(o, "</g>");
        let _ = writeln!(o, r#"<g stroke="black" stroke-width="1">"#);
        for (t, len) in xa.ticks.iter().map(|(t, _)| (*t, 6.0)).chain(xa.minor.iter().map(|t| (*t, 3.0))) {
            let x = sx(t);
            let _ = writeln!(o, r#"<line x1="{x:.2}" y1="{BOTTOM}" x2="{x:.2}" y2="{:.2}"/>"#, BOTTOM + len);
        }
        for (t, len) in ya.ticks.iter().map(|(t, _)| (*t, 6.0)).chain(ya.minor.iter().map(|t| (*t, 3.0))) {
            let y = sy(t);
            let _ = writeln!(o, r#"<line x1="{:.2}" y1="{y:.2}" x2="{LEFT}" y2="{y:.2}"/>"#, LEFT - len);
        }
        let _ = writeln!(o, "</g>");
        let _ = writeln!(
            o,
            r#"<rect x="{LEFT}" y="{TOP}" width="{}" height="{}" fill="none" stroke="black"/>"#,
            RIGHT - LEFT,
            BOTTOM - TOP
        );
        for (t, label) in &xa.ticks {
            let _ = writeln!(
                o,
                r#"<text x="{:.2}" y="{:.2}" text-anchor="middle">{}</text>"#,
                sx(*t),
                BOTTOM + 20.0,
                xml_escape(label)
            );
        }
        for (t, label) in &ya.ticks {
            let _ = writeln!(
                o,
                r#"<text x="{:.2}" y="{:.2}" text-anchor="end">{}</text>"#,
                LEFT - 9.0,
                sy(*t) + 4.0,
                xml_escape(label)
            );
        }

        // Title and axis labels.
        let _ = writeln!(
            o,
            r#"<text x="{:.2}" y="{:.2}" text-anchor="middle" font-size="15">{}</text>"#,
            (LEFT + RIGHT) / 2.0,
            TOP - 15.0,
            xml_escape(&self.title)
        );
        let _ = writeln!(
            o,
            r#"<text x="{:.2}" y="{:.2}" text-anchor="middle">{}</text>"#,
            (LEFT + RIGHT) / 2.0,
            BOTTOM + 45.0,
            xml_escape(&self.x_label)
        );
        let (yl_x, yl_y) = (20.0, (TOP + BOTTOM) / 2.0);
        let _ = writeln!(
            o,
            r#"<text x="{yl_x}" y="{yl_y}" text-anchor="middle" transform="rotate(-90 {yl_x} {yl_y})">{}</text>"#,
            xml_escape(&self.y_label)
        );

        // Data.
        let _ = writeln!(o, r#"<g clip-path="url(#plot-area)">"#);
        let mut screen_lines = Vec::with_capacity(data.len());
        for (i, (s, pts)) in self.series.iter().zip(&data).enumerate() {
            let colour = COLOURS[i % COLOURS.len()];
            let screen: Vec<(f64, f64)> =
                pts.iter().map(|&(x, y)| (sx(x), sy(y))).filter(|(x, y)| x.is_finite() && y.is_finite()).collect();
            let coords: Vec<String> = screen.iter().map(|(x, y)| format!("{x:.2},{y:.2}")).collect();
            let dash = if s.dashed { r#" stroke-dasharray="7,4""# } else { "" };
            let _ = writeln!(
                o,
                r#"<polyline points="{}" fill="none" stroke="{colour}" stroke-width="1.8"{dash}/>"#,
                coords.join(" ")
            );
            let every = screen.len().div_ceil(MAX_MARKERS).max(1);
            for (x, y) in screen.iter().step_by(every) {
                marker(&mut o, i, *x, *y, colour);
            }
            screen_lines.push(screen);
        }
        self.reference_triangles(&mut o, &screen_lines, &xa, &ya);
        let _ = writeln!(o, "</g>");

        // Legend.
        for (i, s) in self.series.iter().enumerate() {
            let colour = COLOURS[i % COLOURS.len()];
            let y = TOP + 10.0 + 20.0 * i as f64;
            let dash = if s.dashed { r#" stroke-dasharray="7,4""# } else { "" };
            let _ = writeln!(
                o,
                r#"<line x1="{LEGEND_X}" y1="{y:.2}" x2="{:.2}" y2="{y:.2}" stroke="{colour}" stroke-width="1.8"{dash}/>"#,
                LEGEND_X + 30.0
            );
            marker(&mut o, i, LEGEND_X + 15.0, y, colour);
            let _ =
                writeln!(o, r#"<text x="{:.2}" y="{:.2}">{}</text>"#, LEGEND_X + 38.0, y + 4.0, xml_escape(&s.label));
        }
        let _ = writeln!(o, "</svg>");
        o
    }

    /// Draws the reference slope triangles where they keep furthest from
    /// the data lines (and from each other), inside the plot area.
    fn reference_triangles(&self, o: &mut String, lines: &[Vec<(f64, f64)>], xa: &Axis, ya: &Axis) {
        let (pw, ph) = (RIGHT - LEFT, BOTTOM - TOP);
        // Pixels per axis unit.
        let kx = pw / (xa.hi - xa.lo);
        let ky = ph / (ya.hi - ya.lo);
        let mut obstacles: Vec<Vec<(f64, f64)>> = lines.to_vec();
        for (slope, label) in &self.reference_slopes {
            if !(slope.is_finite() && kx.is_finite() && ky.is_finite()) {
                continue;
            }
            // Screen size: width 20% of the plot, height at most 30% of it.
            let mut w = 0.2 * pw;
            let mut h = slope.abs() * ky / kx * w;
            if h > 0.3 * ph {
                w *= 0.3 * ph / h;
                h = 0.3 * ph;
            }
            let label_room = 7.0 * label.chars().count() as f64 + 8.0;
            let up = *slope >= 0.0;
            // Left edge range, leaving room for the label beside the
            // vertical leg (right of it when rising, left when falling).
            let (x_min, x_max) = if up {
                (LEFT + 10.0, RIGHT - 10.0 - w - label_room)
            } else {
                (LEFT + 10.0 + label_room, RIGHT - 10.0 - w)
            };
            let (y_min, y_max) = (TOP + 10.0 + h, BOTTOM - 10.0);
            if x_max < x_min || y_max < y_min {
                continue;
            }
            let shape = |x0: f64, y0: f64| {
                // Vertices: start and end of the hypotenuse, right-angle
                // corner (always at the bottom), label anchor.
                if up {
                    ([(x0, y0), (x0 + w, y0 - h), (x0 + w, y0)], (x0 + w + 5.0, y0 - h / 2.0))
                } else {
                    ([(x0, y0 - h), (x0 + w, y0), (x0, y0)], (x0 - 5.0, y0 - h / 2.0))
                }
            };
            let n = 12;
            let mut best: Option<(f64, f64, f64)> = None;
            for i in 0..=n {
                for j in (0..=n).rev() {
                    let x0 = x_min + (x_max - x_min) * i as f64 / n as f64;
                    let y0 = y_min + (y_max - y_min) * j as f64 / n as f64;
                    let (tri, lab) = shape(x0, y0);
                    let mut samples = edge_samples(&tri);
                    let dir = if up { 1.0 } else { -1.0 };
                    samples.extend((0..4).map(|k| (lab.0 + dir * label_room * k as f64 / 3.0, lab.1)));
                    let score = samples.iter().map(|&p| distance_to_lines(p, &obstacles)).fold(f64::INFINITY, f64::min);
                    // Prefer the clearest spot; on ties, the lowest, left-most one.
                    if best.is_none_or(|b| score > b.2 + 1e-9) {
                        best = Some((x0, y0, score));
                    }
                }
            }
            let Some((x0, y0, _)) = best else { continue };
            let (tri, lab) = shape(x0, y0);
            if tri.iter().chain([&lab]).any(|(x, y)| !x.is_finite() || !y.is_finite()) {
                continue;
            }
            let coords: Vec<String> = tri.iter().map(|(x, y)| format!("{x:.2},{y:.2}")).collect();
            let _ = writeln!(
                o,
                r##"<polygon points="{}" fill="none" stroke="#444444" stroke-width="1" stroke-dasharray="3,2"/>"##,
                coords.join(" ")
            );
            let _ = writeln!(
                o,
                r##"<text x="{:.2}" y="{:.2}" text-anchor="{}" fill="#444444">{}</text>"##,
                lab.0,
                lab.1 + 4.0,
                if up { "start" } else { "end" },
                xml_escape(label)
            );
            let mut closed = tri.to_vec();
            closed.push(tri[0]);
            obstacles.push(closed);
            let dir = if up { 1.0 } else { -1.0 };
            obstacles.push(vec![lab, (lab.0 + dir * label_room, lab.1)]);
        }
    }
    /// Writes the SVG to `path`, creating its parent folder if needed.
    pub fn write(&self, path: &Path) -> std::io::Result<()> {
        if let Some(parent) = path.parent() {
            if !parent.as_os_str().is_empty() {
                std::fs::create_dir_all(parent)?;
            }
        }
        std::fs::write(path, self.to_svg())
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

    #[test]
    fn one_polyline_per_series() {
        let svg = convergence_plot().to_svg();
        assert_eq!(svg.matches("<polyline").count(), 3);
        assert!(svg.starts_with("<svg"));
        assert!(svg.trim_end().ends_with("</svg>"));
        assert!(svg.contains("stroke-dasharray=\"7,4\""));
        assert!(svg.contains("rate 2") && svg.contains("rate 1"));
        assert!(svg.contains("Convergence &lt;L2&gt;"));
    }

    #[test]
    fn no_nan_or_inf_text() {
        let mut p = convergence_plot();
        let svg = p.to_svg();
        assert!(!svg.contains("NaN") && !svg.contains("inf"), "{svg}");
        // Linear axes with NaN/inf values, and a plot with no usable data.
        p.log_x = false;
        p.log_y = false;
        p.series.push(Series::new("huge", vec![(f64::INFINITY, 1.0), (1.0, f64::NEG_INFINITY)]));
        let svg = p.to_svg();
        assert!(!svg.contains("NaN") && !svg.contains("inf"));
        let empty = Plot {
            log_x: true,
            log_y: true,
            series: vec![Series::new("none", vec![(-1.0, -1.0)])],
            reference_slopes: vec![(2.0, "r".into())],
            ..Plot::default()
        };
        let svg = empty.to_svg();
        assert!(!svg.contains("NaN") && !svg.contains("inf"));
        assert_eq!(svg.matches("<polyline").count(), 1);
        // Constant data on linear axes.
        let flat = Plot { series: vec![Series::new("c", vec![(1.0, 5.0), (1.0, 5.0)])], ..Plot::default() };
        assert!(!flat.to_svg().contains("NaN"));
    }

    #[test]
    fn log_ticks_at_decades() {
        let (lo, hi, ticks) = log_decades(2e-3f64.log10(), 50f64.log10());
        assert_eq!((lo, hi), (-3, 2));
        assert_eq!(ticks, vec![-3, -2, -1, 0, 1, 2]);
        let svg = Plot {
            log_x: true,
            log_y: true,
            series: vec![Series::new("s", vec![(2e-3, 1.0), (50.0, 10.0)])],
            ..Plot::default()
        }
        .to_svg();
        for label in ["1e-3", "1e-2", "1e-1", "1e0", "1e1", "1e2"] {
            assert!(svg.contains(&format!(">{label}</text>")), "missing {label}");
        }
        // Exactly one decade of data still spans at least one decade.
        let (lo, hi, _) = log_decades(0.0, 0.0);
        assert!(hi > lo);
        // Many decades are thinned to at most ~10 labels, still at decades.
        let (_, _, ticks) = log_decades(-30.0, 10.0);
        assert!(ticks.len() <= 11);
        assert!(ticks.windows(2).all(|w| w[1] - w[0] == ticks[1] - ticks[0]));
    }

    #[test]
    fn nice_linear_ticks() {
        let a = linear_axis(0.03, 0.97);
        assert_eq!((a.lo, a.hi), (0.0, 1.0));
        let labels: Vec<&str> = a.ticks.iter().map(|(_, l)| l.as_str()).collect();
        assert_eq!(labels, ["0", "0.2", "0.4", "0.6", "0.8", "1.0"]);
        let a = linear_axis(-13.0, 42.0);
        let labels: Vec<&str> = a.ticks.iter().map(|(_, l)| l.as_str()).collect();
        assert_eq!(labels, ["-20", "-10", "0", "10", "20", "30", "40", "50"]);
        let a = linear_axis(0.0, 2.5e6);
        assert!(a.ticks.iter().any(|(_, l)| l == "1e6"), "{:?}", a.ticks);
        let close = |a: f64, b: f64| (a - b).abs() <= 1e-12 * b.abs();
        assert!(close(nice_step(0.8), 1.0));
        assert!(close(nice_step(3.0), 2.0));
        assert!(close(nice_step(4.0), 5.0));
        assert!(close(nice_step(0.013), 0.01));
        assert!(close(nice_step(170.0), 200.0));
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
