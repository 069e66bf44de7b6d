//! A small, dependency-free SVG writer for scatter and line plots on linear or logarithmic axes: the
//! figures of `docs/accuracy.md` (drawn by `cli/examples/accuracy.rs`) and of `embedyn tradeoff --svg`.
//!
//! ```
//! use embedyn_cli::plot::{Plot, Series};
//! let svg = Plot::new("ABA error against chain length", "bodies N", "relative error")
//!     .log_x()
//!     .log_y()
//!     .series(Series::new("f64", vec![(10.0, 1e-15), (100.0, 3e-14), (1000.0, 2e-12)]).line(true))
//!     .series(Series::new("f32", vec![(10.0, 1e-6), (100.0, 4e-5), (1000.0, f64::NAN)]))
//!     .to_svg();
//! assert!(svg.starts_with("<svg") && svg.contains("1e-12"));
//! assert!(svg.contains("1 point not shown")); // the NaN: skipped and counted, never a panic
//! ```
//!
//! What it draws: a title, the two axis labels, ticks with labels (every decade `1e-12`, `1e-11`, … on a
//! logarithmic axis, thinned to at most about a dozen; 1, 2 or 5 × 10ᵏ steps on a linear one) and
//! grid lines through them, each series as markers (optionally joined by a line) in a colour of a fixed
//! palette, optional horizontal reference lines, and a legend. A point that cannot be drawn — not finite,
//! or ≤ 0 on a logarithmic axis — is left out, and the number left out is written under the plot; a line
//! is broken where a point was left out. The output is one self-contained SVG document (a `String`),
//! identical for identical input.

use std::fmt::Write as _;

/// The colours series take, in order (then again from the start): a palette that stays distinguishable
/// for the common forms of colour blindness (Okabe and Ito, 2008), black first.
pub const PALETTE: [&str; 8] = [
    "#000000", "#0072B2", "#D55E00", "#009E73", "#CC79A7", "#E69F00", "#56B4E9", "#F0E442",
];

/// The shape drawn at each point of a series.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Marker {
    /// A filled circle.
    Circle,
    /// A filled square.
    Square,
    /// A filled triangle pointing up.
    Triangle,
    /// A filled diamond.
    Diamond,
    /// A diagonal cross (two strokes).
    Cross,
    /// No marker: only the line (if any) shows the series.
    None,
}

/// The markers series take by default, in order of the series (then again from the start).
const MARKERS: [Marker; 5] = [
    Marker::Circle,
    Marker::Square,
    Marker::Triangle,
    Marker::Diamond,
    Marker::Cross,
];

/// One named set of points of a [`Plot`].
#[derive(Clone, Debug)]
pub struct Series {
    name: String,
    points: Vec<(f64, f64)>,
    line: bool,
    dashed: bool,
    marker: Option<Marker>,
    colour: Option<usize>,
}

impl Series {
    /// A series of `(x, y)` points named `name` in the legend: markers only, the next palette colour and
    /// marker of the plot.
    pub fn new(name: impl Into<String>, points: Vec<(f64, f64)>) -> Series {
        Series {
            name: name.into(),
            points,
            line: false,
            dashed: false,
            marker: None,
            colour: None,
        }
    }

    /// Joins consecutive points (in the order given) by a line.
    pub fn line(mut self, on: bool) -> Series {
        self.line = on;
        self
    }

    /// Draws the joining line dashed (it implies `line(true)`).
    pub fn dashed(mut self) -> Series {
        self.line = true;
        self.dashed = true;
        self
    }

    /// The marker drawn at each point instead of the plot's next one.
    pub fn marker(mut self, marker: Marker) -> Series {
        self.marker = Some(marker);
        self
    }

    /// The colour `PALETTE[index % PALETTE.len()]` instead of the plot's next one (to give related
    /// series, say f32 and f64 of one algorithm, one colour).
    pub fn colour(mut self, index: usize) -> Series {
        self.colour = Some(index);
        self
    }
}

/// A plot: axes, series, legend; [`Plot::to_svg`] writes it.
#[derive(Clone, Debug)]
pub struct Plot {
    title: String,
    x_label: String,
    y_label: String,
    log_x: bool,
    log_y: bool,
    series: Vec<Series>,
    hlines: Vec<(f64, String)>,
    width: f64,
    height: f64,
}

/// The drawing area's margins in pixels: left (tick labels and the y label), right (the legend is set
/// apart), top (title), bottom (tick labels, x label, note).
const MARGIN_LEFT: f64 = 78.0;
const MARGIN_TOP: f64 = 40.0;
const MARGIN_BOTTOM: f64 = 70.0;
const MARGIN_RIGHT: f64 = 16.0;
/// Roughly the width of one character of the 12 px sans-serif text (for the legend's box).
const CHAR_WIDTH: f64 = 6.6;

impl Plot {
    /// An empty plot, linear axes, 720 × 440 pixels.
    pub fn new(
        title: impl Into<String>,
        x_label: impl Into<String>,
        y_label: impl Into<String>,
    ) -> Plot {
        Plot {
            title: title.into(),
            x_label: x_label.into(),
            y_label: y_label.into(),
            log_x: false,
            log_y: false,
            series: Vec::new(),
            hlines: Vec::new(),
            width: 720.0,
            height: 440.0,
        }
    }

    /// A logarithmic x axis (base 10).
    pub fn log_x(mut self) -> Plot {
        self.log_x = true;
        self
    }

    /// A logarithmic y axis (base 10).
    pub fn log_y(mut self) -> Plot {
        self.log_y = true;
        self
    }

    /// The size of the picture in pixels (each clamped to at least 240 × 200).
    pub fn size(mut self, width: f64, height: f64) -> Plot {
        self.width = if width.is_finite() {
            width.max(240.0)
        } else {
            720.0
        };
        self.height = if height.is_finite() {
            height.max(200.0)
        } else {
            440.0
        };
        self
    }

    /// Adds a series.
    pub fn series(mut self, series: Series) -> Plot {
        self.series.push(series);
        self
    }

    /// A horizontal grey dashed reference line at `y` (say machine epsilon, or a threshold), labelled at
    /// its left end; it widens the y range to include itself. Left out like a point if it cannot be drawn.
    pub fn hline(mut self, y: f64, label: impl Into<String>) -> Plot {
        self.hlines.push((y, label.into()));
        self
    }

    /// The SVG document.
    pub fn to_svg(&self) -> String {
        let drawable = |log: bool, v: f64| v.is_finite() && (!log || v > 0.0);
        let mut skipped = 0usize;
        let mut xs = Vec::new();
        let mut ys = Vec::new();
        for s in &self.series {
            for &(x, y) in &s.points {
                if drawable(self.log_x, x) && drawable(self.log_y, y) {
                    xs.push(x);
                    ys.push(y);
                } else {
                    skipped += 1;
                }
            }
        }
        for (y, _) in &self.hlines {
            if drawable(self.log_y, *y) {
                ys.push(*y);
            } else {
                skipped += 1;
            }
        }
        let x_axis = Axis::new(self.log_x, &xs);
        let y_axis = Axis::new(self.log_y, &ys);

        let legend_width = self
            .series
            .iter()
            .map(|s| s.name.chars().count())
            .max()
            .map_or(0.0, |n| 44.0 + n as f64 * CHAR_WIDTH);
        let (w, h) = (self.width, self.height);
        let left = MARGIN_LEFT;
        let right = w
            - MARGIN_RIGHT
            - if legend_width > 0.0 {
                legend_width + 12.0
            } else {
                0.0
            };
        let right = right.max(left + 60.0);
        let top = MARGIN_TOP;
        let bottom = h - MARGIN_BOTTOM;
        let px = |x: f64| left + x_axis.fraction(x) * (right - left);
        let py = |y: f64| bottom - y_axis.fraction(y) * (bottom - top);
        // Ticks are placed by their position in axis units (a decade's exponent on a logarithmic axis,
        // which stays finite where 10^e would underflow).
        let px_units = |u: f64| left + x_axis.fraction_of_units(u) * (right - left);
        let py_units = |u: f64| bottom - y_axis.fraction_of_units(u) * (bottom - top);

        let mut svg = String::new();
        let _ = writeln!(
            svg,
            r#"<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{h}" viewBox="0 0 {w} {h}" font-family="sans-serif" font-size="12">"#
        );
        let _ = writeln!(
            svg,
            r#"<rect x="0" y="0" width="{w}" height="{h}" fill="white"/>"#
        );
        let _ = writeln!(
            svg,
            r#"<text x="{}" y="24" text-anchor="middle" font-size="15" font-weight="bold">{}</text>"#,
            fmt((left + right) / 2.0),
            escape(&self.title)
        );

        // Grid and ticks.
        for (units, label) in x_axis.ticks() {
            let x = fmt(px_units(units));
            let _ = writeln!(
                svg,
                r##"<line x1="{x}" y1="{}" x2="{x}" y2="{}" stroke="#dddddd" stroke-width="1"/>"##,
                fmt(top),
                fmt(bottom)
            );
            let _ = writeln!(
                svg,
                r#"<text class="xtick" x="{x}" y="{}" text-anchor="middle">{}</text>"#,
                fmt(bottom + 16.0),
                escape(&label)
            );
        }
        for (units, label) in y_axis.ticks() {
            let y = fmt(py_units(units));
            let _ = writeln!(
                svg,
                r##"<line x1="{}" y1="{y}" x2="{}" y2="{y}" stroke="#dddddd" stroke-width="1"/>"##,
                fmt(left),
                fmt(right)
            );
            let _ = writeln!(
                svg,
                r#"<text class="ytick" x="{}" y="{y}" text-anchor="end" dominant-baseline="middle">{}</text>"#,
                fmt(left - 6.0),
                escape(&label)
            );
        }
        let _ = writeln!(
            svg,
            r#"<rect x="{}" y="{}" width="{}" height="{}" fill="none" stroke="black" stroke-width="1"/>"#,
            fmt(left),
            fmt(top),
            fmt(right - left),
            fmt(bottom - top)
        );
        let _ = writeln!(
            svg,
            r#"<text x="{}" y="{}" text-anchor="middle">{}</text>"#,
            fmt((left + right) / 2.0),
            fmt(bottom + 36.0),
            escape(&self.x_label)
        );
        let (yx, yy) = (fmt(18.0), fmt((top + bottom) / 2.0));
        let _ = writeln!(
            svg,
            r#"<text x="{yx}" y="{yy}" text-anchor="middle" transform="rotate(-90 {yx} {yy})">{}</text>"#,
            escape(&self.y_label)
        );

        // Reference lines.
        for (y, label) in &self.hlines {
            if !drawable(self.log_y, *y) {
                continue;
            }
            let yp = fmt(py(*y));
            let _ = writeln!(
                svg,
                r##"<line x1="{}" y1="{yp}" x2="{}" y2="{yp}" stroke="#888888" stroke-width="1" stroke-dasharray="6 4"/>"##,
                fmt(left),
                fmt(right)
            );
            let _ = writeln!(
                svg,
                r##"<text x="{}" y="{}" fill="#666666" font-size="11">{}</text>"##,
                fmt(left + 4.0),
                fmt(py(*y) - 3.0),
                escape(label)
            );
        }

        // Series, clipped to the drawing area.
        let _ = writeln!(
            svg,
            r#"<clipPath id="area"><rect x="{}" y="{}" width="{}" height="{}"/></clipPath>"#,
            fmt(left - 5.0),
            fmt(top - 5.0),
            fmt(right - left + 10.0),
            fmt(bottom - top + 10.0)
        );
        let _ = writeln!(svg, r#"<g clip-path="url(#area)">"#);
        for (k, s) in self.series.iter().enumerate() {
            let colour = PALETTE[s.colour.unwrap_or(k) % PALETTE.len()];
            let marker = s.marker.unwrap_or(MARKERS[k % MARKERS.len()]);
            if s.line {
                // One polyline per run of drawable points.
                let mut runs: Vec<Vec<(f64, f64)>> = vec![Vec::new()];
                for &(x, y) in &s.points {
                    if drawable(self.log_x, x) && drawable(self.log_y, y) {
                        runs.last_mut().expect("never empty").push((px(x), py(y)));
                    } else if !runs.last().expect("never empty").is_empty() {
                        runs.push(Vec::new());
                    }
                }
                for run in runs.iter().filter(|r| r.len() > 1) {
                    let points: Vec<String> = run
                        .iter()
                        .map(|(x, y)| format!("{},{}", fmt(*x), fmt(*y)))
                        .collect();
                    let _ = writeln!(
                        svg,
                        r#"<polyline points="{}" fill="none" stroke="{colour}" stroke-width="1.5"{}/>"#,
                        points.join(" "),
                        if s.dashed {
                            r#" stroke-dasharray="5 3""#
                        } else {
                            ""
                        }
                    );
                }
            }
            for &(x, y) in &s.points {
                if drawable(self.log_x, x) && drawable(self.log_y, y) {
                    draw_marker(&mut svg, marker, px(x), py(y), colour);
                }
            }
        }
        let _ = writeln!(svg, "</g>");

        // Legend.
        if legend_width > 0.0 {
            let lx = right + 12.0;
            let ly = top;
            let _ = writeln!(
                svg,
                r##"<rect x="{}" y="{}" width="{}" height="{}" fill="white" stroke="#999999" stroke-width="1"/>"##,
                fmt(lx),
                fmt(ly),
                fmt(legend_width),
                fmt(8.0 + 18.0 * self.series.len() as f64)
            );
            for (k, s) in self.series.iter().enumerate() {
                let colour = PALETTE[s.colour.unwrap_or(k) % PALETTE.len()];
                let marker = s.marker.unwrap_or(MARKERS[k % MARKERS.len()]);
                let y = ly + 14.0 + 18.0 * k as f64;
                if s.line {
                    let _ = writeln!(
                        svg,
                        r#"<line x1="{}" y1="{}" x2="{}" y2="{}" stroke="{colour}" stroke-width="1.5"{}/>"#,
                        fmt(lx + 6.0),
                        fmt(y),
                        fmt(lx + 30.0),
                        fmt(y),
                        if s.dashed {
                            r#" stroke-dasharray="5 3""#
                        } else {
                            ""
                        }
                    );
                }
                draw_marker(&mut svg, marker, lx + 18.0, y, colour);
                let _ = writeln!(
                    svg,
                    r#"<text class="legend" x="{}" y="{}" dominant-baseline="middle">{}</text>"#,
                    fmt(lx + 36.0),
                    fmt(y),
                    escape(&s.name)
                );
            }
        }

        if skipped > 0 {
            let _ = writeln!(
                svg,
                r##"<text class="note" x="{}" y="{}" fill="#666666" font-size="11">{skipped} point{} not shown (not finite, or ≤ 0 on a logarithmic axis)</text>"##,
                fmt(left),
                fmt(h - 10.0),
                if skipped == 1 { "" } else { "s" }
            );
        }
        svg.push_str("</svg>\n");
        svg
    }
}

/// One axis: its range in plot units (log10 of the value on a logarithmic axis).
struct Axis {
    log: bool,
    lo: f64,
    hi: f64,
}

impl Axis {
    /// The axis spanning `values` (all drawable): whole decades on a logarithmic axis, a multiple of the
    /// tick step on a linear one; a default range when there is nothing to span.
    fn new(log: bool, values: &[f64]) -> Axis {
        let (mut min, mut max) = (f64::INFINITY, f64::NEG_INFINITY);
        for &v in values {
            let u = if log { v.log10() } else { v };
            min = min.min(u);
            max = max.max(u);
        }
        if log {
            if min > max {
                return Axis {
                    log,
                    lo: 0.0,
                    hi: 1.0,
                };
            }
            let (lo, mut hi) = (min.floor(), max.ceil());
            if hi <= lo {
                hi = lo + 1.0;
            }
            Axis { log, lo, hi }
        } else {
            if min > max {
                return Axis {
                    log,
                    lo: 0.0,
                    hi: 1.0,
                };
            }
            if max - min <= f64::EPSILON * max.abs().max(min.abs()).max(f64::MIN_POSITIVE) {
                let pad = if min == 0.0 { 1.0 } else { min.abs() * 0.1 };
                min -= pad;
                max += pad;
            }
            let step = linear_step(min, max);
            let (lo, hi) = ((min / step).floor() * step, (max / step).ceil() * step);
            if !(lo.is_finite() && hi.is_finite()) || hi <= lo {
                return Axis {
                    log,
                    lo: min,
                    hi: max,
                };
            }
            Axis { log, lo, hi }
        }
    }

    /// Where `value` falls, 0 at the low end and 1 at the high end.
    fn fraction(&self, value: f64) -> f64 {
        self.fraction_of_units(if self.log { value.log10() } else { value })
    }

    /// Where a position in axis units (log10 of the value on a logarithmic axis) falls. Halved first, so
    /// that a span of the whole f64 range does not overflow.
    fn fraction_of_units(&self, u: f64) -> f64 {
        (u * 0.5 - self.lo * 0.5) / (self.hi * 0.5 - self.lo * 0.5)
    }

    /// The ticks: `(position in axis units, label)`.
    fn ticks(&self) -> Vec<(f64, String)> {
        if self.log {
            let (lo, hi) = (self.lo as i64, self.hi as i64);
            let every = ((hi - lo) as f64 / 12.0).ceil().max(1.0) as i64;
            (lo..=hi)
                .filter(|e| (e - lo) % every == 0)
                .map(|e| (e as f64, format!("1e{e}")))
                .collect()
        } else {
            let step = linear_step(self.lo, self.hi);
            // A little slack: the range's ends are multiples of the step up to rounding.
            let first = (self.lo / step - 1e-9).ceil() as i64;
            let last = (self.hi / step + 1e-9).floor() as i64;
            if last - first > 100 {
                return Vec::new(); // A degenerate range: no ticks rather than thousands.
            }
            (first..=last)
                .map(|k| {
                    let v = k as f64 * step;
                    (v, linear_label(v, step))
                })
                .collect()
        }
    }
}

/// The tick step between `lo` and `hi` (`lo < hi`): 1, 2 or 5 × 10ᵏ, giving 4 to 10 ticks (the span is
/// halved first, so that a span beyond `f64::MAX` does not overflow).
fn linear_step(lo: f64, hi: f64) -> f64 {
    let raw = (hi * 0.5 - lo * 0.5) / 3.0;
    let decade = 10f64.powf(raw.log10().floor());
    let m = raw / decade;
    let nice = if m < 1.5 {
        1.0
    } else if m < 3.5 {
        2.0
    } else if m < 7.5 {
        5.0
    } else {
        10.0
    };
    nice * decade
}

/// A linear tick's label: as many decimals as the step needs, `-0` written as `0`.
fn linear_label(v: f64, step: f64) -> String {
    let magnitude = v.abs().max(step);
    if !(1e-4..1e6).contains(&magnitude) {
        return format!("{v:e}");
    }
    let decimals = (-step.log10().floor()).max(0.0) as usize;
    let s = format!("{v:.decimals$}");
    if s.trim_start_matches('-')
        .chars()
        .all(|c| c == '0' || c == '.')
    {
        "0".to_string()
    } else {
        s
    }
}

fn draw_marker(svg: &mut String, marker: Marker, x: f64, y: f64, colour: &str) {
    let r = 3.5;
    let _ = match marker {
        Marker::Circle => writeln!(
            svg,
            r#"<circle cx="{}" cy="{}" r="{r}" fill="{colour}"/>"#,
            fmt(x),
            fmt(y)
        ),
        Marker::Square => writeln!(
            svg,
            r#"<rect x="{}" y="{}" width="{}" height="{}" fill="{colour}"/>"#,
            fmt(x - r),
            fmt(y - r),
            fmt(2.0 * r),
            fmt(2.0 * r)
        ),
        Marker::Triangle => writeln!(
            svg,
            r#"<polygon points="{},{} {},{} {},{}" fill="{colour}"/>"#,
            fmt(x),
            fmt(y - 1.2 * r),
            fmt(x - 1.1 * r),
            fmt(y + 0.9 * r),
            fmt(x + 1.1 * r),
            fmt(y + 0.9 * r)
        ),
        Marker::Diamond => writeln!(
            svg,
            r#"<polygon points="{},{} {},{} {},{} {},{}" fill="{colour}"/>"#,
            fmt(x),
            fmt(y - 1.3 * r),
            fmt(x + r),
            fmt(y),
            fmt(x),
            fmt(y + 1.3 * r),
            fmt(x - r),
            fmt(y)
        ),
        Marker::Cross => writeln!(
            svg,
            r#"<path d="M{} {}L{} {}M{} {}L{} {}" stroke="{colour}" stroke-width="1.8"/>"#,
            fmt(x - r),
            fmt(y - r),
            fmt(x + r),
            fmt(y + r),
            fmt(x - r),
            fmt(y + r),
            fmt(x + r),
            fmt(y - r)
        ),
        Marker::None => Ok(()),
    };
}

/// A coordinate with two decimals (the picture needs no more; the document stays small).
fn fmt(v: f64) -> String {
    let s = format!("{v:.2}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s == "-0" {
        "0".to_string()
    } else {
        s.to_string()
    }
}

/// Text as XML character data or an attribute value.
fn escape(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&apos;"),
            // Control characters are not allowed in XML 1.0 (tab and newline are, but mean nothing here).
            c if c.is_control() => out.push(' '),
            c => out.push(c),
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(svg: &str) -> roxmltree::Document<'_> {
        roxmltree::Document::parse(svg).unwrap_or_else(|e| panic!("not XML: {e}\n{svg}"))
    }

    /// The labels and positions of the text elements of one class.
    fn texts(doc: &roxmltree::Document<'_>, class: &str, coordinate: &str) -> Vec<(String, f64)> {
        doc.descendants()
            .filter(|n| n.attribute("class") == Some(class))
            .map(|n| {
                let at: f64 = n.attribute(coordinate).unwrap().parse().unwrap();
                (n.text().unwrap_or("").to_string(), at)
            })
            .collect()
    }

    #[test]
    fn log_log_plot_is_xml_with_decade_ticks_evenly_spaced() {
        let svg = Plot::new("Error & <chain>", "N", "relative error")
            .log_x()
            .log_y()
            .series(Series::new("f64 \"aba\"", vec![(10.0, 1e-15), (1000.0, 2e-12)]).line(true))
            .series(Series::new("f32", vec![(10.0, 3e-7), (200.0, 1e-3)]).dashed())
            .to_svg();
        let doc = parse(&svg);
        assert_eq!(doc.root_element().tag_name().name(), "svg");
        let x: Vec<_> = texts(&doc, "xtick", "x");
        let labels: Vec<&str> = x.iter().map(|(l, _)| l.as_str()).collect();
        assert_eq!(labels, ["1e1", "1e2", "1e3"]);
        assert!((x[1].1 - x[0].1 - (x[2].1 - x[1].1)).abs() < 0.02, "{x:?}");
        let y: Vec<_> = texts(&doc, "ytick", "y");
        let labels: Vec<&str> = y.iter().map(|(l, _)| l.as_str()).collect();
        assert_eq!(labels.first(), Some(&"1e-15"));
        assert_eq!(labels.last(), Some(&"1e-3"));
        assert_eq!(labels.len(), 13);
        // Higher values higher up: SVG's y grows downwards.
        assert!(y.windows(2).all(|w| w[1].1 < w[0].1));
        let steps: Vec<f64> = y.windows(2).map(|w| w[0].1 - w[1].1).collect();
        assert!(
            steps.iter().all(|s| (s - steps[0]).abs() < 0.02),
            "{steps:?}"
        );
        // The escaped names come back as written.
        let legend: Vec<_> = texts(&doc, "legend", "x")
            .into_iter()
            .map(|(l, _)| l)
            .collect();
        assert_eq!(legend, ["f64 \"aba\"", "f32"]);
        assert!(doc
            .descendants()
            .any(|n| n.text() == Some("Error & <chain>")));
        assert_eq!(
            doc.descendants()
                .filter(|n| n.has_tag_name("polyline"))
                .count(),
            2
        );
        assert!(!svg.contains("not shown"));
    }

    #[test]
    fn many_decades_are_thinned_to_about_a_dozen_labels() {
        let svg = Plot::new("t", "x", "y")
            .log_x()
            .log_y()
            .series(Series::new("s", vec![(1e-30, 1.0), (1e30, 2.0)]))
            .to_svg();
        let doc = parse(&svg);
        let x = texts(&doc, "xtick", "x");
        assert!((7..=13).contains(&x.len()), "{x:?}");
        assert_eq!(x[0].0, "1e-30");
        assert_eq!(x.last().unwrap().0, "1e30");
        // A single decade of y still gets two ticks.
        let y = texts(&doc, "ytick", "y");
        assert_eq!(
            y.iter().map(|(l, _)| l.as_str()).collect::<Vec<_>>(),
            ["1e0", "1e1"]
        );
    }

    #[test]
    fn undrawable_points_are_skipped_counted_and_break_the_line() {
        let points = vec![
            (1.0, 1e-3),
            (2.0, 1e-4),
            (3.0, f64::NAN),
            (4.0, 0.0),
            (5.0, -1.0),
            (6.0, f64::INFINITY),
            (7.0, 1e-5),
            (8.0, 1e-6),
        ];
        let svg = Plot::new("t", "x", "y")
            .log_y()
            .series(Series::new("s", points).line(true))
            .hline(-1.0, "not drawable")
            .to_svg();
        let doc = parse(&svg);
        let note: Vec<_> = texts(&doc, "note", "x");
        assert!(note[0].0.starts_with("5 points not shown"), "{note:?}");
        // Two runs of two points each: two polylines, not one through the gap.
        assert_eq!(
            doc.descendants()
                .filter(|n| n.has_tag_name("polyline"))
                .count(),
            2
        );
        // Lin–log: linear x ticks at a nice step.
        let x = texts(&doc, "xtick", "x");
        let labels: Vec<&str> = x.iter().map(|(l, _)| l.as_str()).collect();
        assert_eq!(labels, ["1", "2", "3", "4", "5", "6", "7", "8"]);
    }

    #[test]
    fn degenerate_input_gives_a_valid_picture() {
        for plot in [
            Plot::new("", "", ""),
            Plot::new("empty", "x", "y").log_x().log_y(),
            Plot::new("nothing drawable", "x", "y")
                .log_x()
                .series(Series::new("s", vec![(0.0, 1.0), (f64::NAN, f64::NAN)])),
            Plot::new("one point", "x", "y").series(Series::new("s", vec![(3.0, 3.0)])),
            Plot::new("zero", "x", "y").series(Series::new("s", vec![(0.0, 0.0)])),
            Plot::new("huge", "x", "y").series(Series::new(
                "s",
                vec![(-f64::MAX, 1e300), (f64::MAX, -1e300)],
            )),
            Plot::new("tiny", "x", "y")
                .log_x()
                .log_y()
                .series(Series::new(
                    "s",
                    vec![(f64::MIN_POSITIVE, 5e-324), (f64::MAX, 1.0)],
                ))
                .size(f64::NAN, 0.0),
            Plot::new("ctl\u{1}chars", "x", "y").series(Series::new("\u{0}", vec![(1.0, 2.0)])),
        ] {
            let svg = plot.to_svg();
            parse(&svg);
            assert!(!svg.contains("NaN") && !svg.contains("inf"), "{svg}");
        }
    }

    #[test]
    fn linear_ticks_are_round_numbers() {
        let axis = Axis::new(false, &[0.0, 10.0]);
        let labels: Vec<String> = axis.ticks().into_iter().map(|(_, l)| l).collect();
        assert_eq!(labels, ["0", "2", "4", "6", "8", "10"]);
        let axis = Axis::new(false, &[-0.3, 0.25]);
        let labels: Vec<String> = axis.ticks().into_iter().map(|(_, l)| l).collect();
        assert_eq!(labels, ["-0.3", "-0.2", "-0.1", "0", "0.1", "0.2", "0.3"]);
    }

    #[test]
    fn same_input_same_document() {
        let make = || {
            Plot::new("t", "x", "y")
                .log_y()
                .series(
                    Series::new("a", vec![(1.0, 1.0), (2.0, 10.0)])
                        .colour(3)
                        .marker(Marker::Cross),
                )
                .hline(5.0, "five")
                .to_svg()
        };
        assert_eq!(make(), make());
        assert!(make().contains(PALETTE[3]));
    }
}
