//! Charts as inline SVG, drawn from numbers the page is given: scatter points, arrows, horizontal bars
//! with whiskers — each with its axes, ticks at round numbers and axis labels with their units. A chart
//! scales with the page (a `viewBox`, no fixed size), so it reads on a phone as on a laptop.

use std::fmt::Write;

use crate::html::escape;

/// Width and height of a chart's drawing, in the `viewBox`'s units.
const WIDTH: f64 = 640.0;
const HEIGHT: f64 = 400.0;
/// Margins: left (tick labels and the y label), right, top (title), bottom (tick labels and the x label).
const LEFT: f64 = 72.0;
const RIGHT: f64 = 16.0;
const TOP: f64 = 30.0;
const BOTTOM: f64 = 52.0;

/// A colour of the page's palette (readable on white, told apart without colour vision: grey and blue differ in lightness).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Colour {
    /// Before: the nominal model.
    Grey,
    /// After: the final model.
    Blue,
}

impl Colour {
    fn css(self) -> &'static str {
        match self {
            Colour::Grey => "#8c8c8c",
            Colour::Blue => "#1f5fbf",
        }
    }
}

/// An axis: its label with the unit, and the range shown.
#[derive(Clone, Debug)]
pub(crate) struct Axis {
    pub(crate) label: String,
    pub(crate) lo: f64,
    pub(crate) hi: f64,
}

impl Axis {
    /// The axis over `values` (with 4 % of room at either end; a span of zero opened to ±1).
    pub(crate) fn over(label: impl Into<String>, values: impl IntoIterator<Item = f64>) -> Self {
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        for v in values.into_iter().filter(|v| v.is_finite()) {
            lo = lo.min(v);
            hi = hi.max(v);
        }
        if !lo.is_finite() {
            (lo, hi) = (0.0, 1.0);
        }
        if hi - lo <= 0.0 {
            (lo, hi) = (lo - 1.0, hi + 1.0);
        }
        let room = 0.04 * (hi - lo);
        Self { label: label.into(), lo: lo - room, hi: hi + room }
    }

    /// The same axis starting at zero (a non-negative quantity: an error's size).
    pub(crate) fn starting_at_zero(mut self) -> Self {
        self.lo = 0.0;
        self
    }
}

/// What a chart draws.
pub(crate) enum Layer {
    /// Points at `(x, y)`.
    Points { points: Vec<(f64, f64)>, colour: Colour, label: String },
    /// Arrows from `(x, y)` by `(dx, dy)` (in the axes' units).
    Arrows { arrows: Vec<((f64, f64), (f64, f64))>, colour: Colour, label: String },
}

/// A chart of points and arrows on two axes.
pub(crate) struct Chart {
    pub(crate) title: String,
    pub(crate) x: Axis,
    pub(crate) y: Axis,
    /// One millimetre is as long on both axes (a view of the workspace).
    pub(crate) equal_scale: bool,
    pub(crate) layers: Vec<Layer>,
}

/// Round tick values covering `lo..hi`: steps of 1, 2 or 5 × 10ⁿ, about `count` of them.
pub(crate) fn ticks(lo: f64, hi: f64, count: usize) -> Vec<f64> {
    let span = hi - lo;
    if !(span > 0.0 && span.is_finite()) {
        return vec![lo];
    }
    let raw = span / count.max(1) as f64;
    let magnitude = 10f64.powf(raw.log10().floor());
    let step = [1.0, 2.0, 5.0, 10.0].iter().map(|m| m * magnitude).find(|s| *s >= raw).unwrap_or(10.0 * magnitude);
    let first = (lo / step).ceil() as i64;
    let last = (hi / step).floor() as i64;
    (first..=last).map(|k| k as f64 * step).collect()
}

/// A tick label with as many decimals as the step needs.
pub(crate) fn tick_label(v: f64, step: f64) -> String {
    let decimals = if step >= 1.0 { 0 } else { (-step.log10().floor()) as usize };
    let text = format!("{v:.decimals$}");
    if text.starts_with('-') && text.trim_start_matches(['-', '0', '.']).is_empty() {
        text[1..].to_string()
    } else {
        text
    }
}

/// The mapping of data to drawing coordinates.
struct Frame {
    x0: f64,
    x1: f64,
    y0: f64,
    y1: f64,
    left: f64,
    top: f64,
    width: f64,
    height: f64,
}

impl Frame {
    fn px(&self, x: f64) -> f64 {
        self.left + (x - self.x0) / (self.x1 - self.x0) * self.width
    }
    fn py(&self, y: f64) -> f64 {
        self.top + self.height - (y - self.y0) / (self.y1 - self.y0) * self.height
    }
}

/// The opening tag of a chart, with its accessible name.
fn open(out: &mut String, title: &str, height: f64) {
    let _ = write!(
        out,
        r#"<svg class="chart" viewBox="0 0 {WIDTH} {height}" role="img" aria-label="{t}"><title>{t}</title><rect width="{WIDTH}" height="{height}" fill="white"/><text x="{LEFT}" y="20" class="ct">{t}</text>"#,
        t = escape(title)
    );
}

/// The axes' lines, ticks, tick labels and axis labels.
fn axes(out: &mut String, f: &Frame, x: &Axis, y: &Axis) {
    let (bottom, right) = (f.top + f.height, f.left + f.width);
    let _ = write!(
        out,
        r#"<g class="ax"><rect x="{}" y="{}" width="{}" height="{}" fill="none"/>"#,
        f.left, f.top, f.width, f.height
    );
    let xt = ticks(f.x0, f.x1, 6);
    let xstep = if xt.len() > 1 { xt[1] - xt[0] } else { 1.0 };
    for v in &xt {
        let px = f.px(*v);
        let _ = write!(
            out,
            r#"<line x1="{px:.1}" y1="{bottom}" x2="{px:.1}" y2="{}"/><line class="grid" x1="{px:.1}" y1="{}" x2="{px:.1}" y2="{bottom}"/><text x="{px:.1}" y="{}" text-anchor="middle">{}</text>"#,
            bottom + 5.0,
            f.top,
            bottom + 18.0,
            tick_label(*v, xstep)
        );
    }
    let yt = ticks(f.y0, f.y1, 5);
    let ystep = if yt.len() > 1 { yt[1] - yt[0] } else { 1.0 };
    for v in &yt {
        let py = f.py(*v);
        let _ = write!(
            out,
            r#"<line x1="{}" y1="{py:.1}" x2="{}" y2="{py:.1}"/><line class="grid" x1="{}" y1="{py:.1}" x2="{right}" y2="{py:.1}"/><text x="{}" y="{:.1}" text-anchor="end">{}</text>"#,
            f.left - 5.0,
            f.left,
            f.left,
            f.left - 8.0,
            py + 4.0,
            tick_label(*v, ystep)
        );
    }
    let _ = write!(
        out,
        r#"<text x="{:.1}" y="{:.1}" text-anchor="middle">{}</text><text transform="translate(16 {:.1}) rotate(-90)" text-anchor="middle">{}</text></g>"#,
        f.left + f.width / 2.0,
        bottom + 40.0,
        escape(&x.label),
        f.top + f.height / 2.0,
        escape(&y.label)
    );
}

impl Chart {
    /// The chart as an `<svg>` element.
    pub(crate) fn svg(&self) -> String {
        let (mut x, mut y) = (self.x.clone(), self.y.clone());
        let (width, height) = (WIDTH - LEFT - RIGHT, HEIGHT - TOP - BOTTOM);
        if self.equal_scale {
            // Widen the axis whose millimetres would be longer, about its centre.
            let (sx, sy) = ((x.hi - x.lo) / width, (y.hi - y.lo) / height);
            if sx > sy {
                let c = 0.5 * (y.lo + y.hi);
                (y.lo, y.hi) = (c - 0.5 * sx * height, c + 0.5 * sx * height);
            } else {
                let c = 0.5 * (x.lo + x.hi);
                (x.lo, x.hi) = (c - 0.5 * sy * width, c + 0.5 * sy * width);
            }
        }
        let f = Frame { x0: x.lo, x1: x.hi, y0: y.lo, y1: y.hi, left: LEFT, top: TOP, width, height };
        let mut out = String::new();
        open(&mut out, &self.title, HEIGHT);
        axes(&mut out, &f, &x, &y);
        let clip = format!("c{:x}", fxhash(&self.title));
        let _ = write!(
            out,
            r#"<clipPath id="{clip}"><rect x="{}" y="{}" width="{}" height="{}"/></clipPath><g clip-path="url(#{clip})">"#,
            f.left, f.top, f.width, f.height
        );
        let mut legend = Vec::new();
        for layer in &self.layers {
            match layer {
                Layer::Points { points, colour, label } => {
                    let _ = write!(out, r#"<g fill="{}" fill-opacity="0.55">"#, colour.css());
                    for &(px, py) in points.iter().filter(|(a, b)| a.is_finite() && b.is_finite()) {
                        let _ = write!(out, r#"<circle cx="{:.1}" cy="{:.1}" r="1.8"/>"#, f.px(px), f.py(py));
                    }
                    out.push_str("</g>");
                    legend.push((label.clone(), *colour));
                }
                Layer::Arrows { arrows, colour, label } => {
                    let _ = write!(out, r#"<g stroke="{}" stroke-width="1" fill="none">"#, colour.css());
                    for &((ax, ay), (dx, dy)) in arrows {
                        let (x0, y0, x1, y1) = (f.px(ax), f.py(ay), f.px(ax + dx), f.py(ay + dy));
                        if [x0, y0, x1, y1].iter().all(|v| v.is_finite()) {
                            let _ = write!(out, r#"<path d="M{x0:.1} {y0:.1}L{x1:.1} {y1:.1}"/>"#);
                            let _ =
                                write!(out, r#"<circle cx="{x1:.1}" cy="{y1:.1}" r="1.2" fill="{}"/>"#, colour.css());
                        }
                    }
                    out.push_str("</g>");
                    legend.push((label.clone(), *colour));
                }
            }
        }
        out.push_str("</g>");
        legend_box(&mut out, &legend, f.left + f.width - 8.0, f.top + 8.0);
        out.push_str("</svg>");
        out
    }
}

/// The legend, right-aligned at `(right, top)`.
fn legend_box(out: &mut String, legend: &[(String, Colour)], right: f64, top: f64) {
    for (k, (label, colour)) in legend.iter().enumerate() {
        let y = top + 14.0 * k as f64;
        let _ = write!(
            out,
            r#"<rect x="{:.1}" y="{:.1}" width="10" height="10" fill="{}"/><text x="{:.1}" y="{:.1}" text-anchor="end" class="lg">{}</text>"#,
            right - 10.0,
            y,
            colour.css(),
            right - 14.0,
            y + 9.0,
            escape(label)
        );
    }
}

/// A short deterministic name for a chart's clip path (charts of one page never share one).
fn fxhash(s: &str) -> u64 {
    s.bytes().fold(0xcbf2_9ce4_8422_2325u64, |h, b| (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3))
}

/// One group of a bar chart: its label and one value per series, each with an optional whisker.
pub(crate) struct BarGroup {
    pub(crate) label: String,
    pub(crate) values: Vec<(f64, Option<(f64, f64)>)>,
}

/// Horizontal bars: one group per row (labels on the left), one bar per series, on a value axis.
pub(crate) struct Bars {
    pub(crate) title: String,
    pub(crate) value_label: String,
    pub(crate) series: Vec<(String, Colour)>,
    pub(crate) groups: Vec<BarGroup>,
}

impl Bars {
    /// The chart as an `<svg>` element; its height grows with the groups.
    pub(crate) fn svg(&self) -> String {
        let label_width = 250.0;
        let bar = 12.0;
        let group_height = bar * self.series.len().max(1) as f64 + 10.0;
        let legend_height = 16.0 * self.series.len() as f64;
        let top = TOP + legend_height;
        let height = top + group_height * self.groups.len().max(1) as f64 + BOTTOM;
        let values = self
            .groups
            .iter()
            .flat_map(|g| g.values.iter().flat_map(|(v, w)| [Some(*v), w.map(|w| w.1)]).flatten().collect::<Vec<_>>());
        let axis = Axis::over(self.value_label.clone(), values).starting_at_zero();
        let f = Frame {
            x0: axis.lo,
            x1: axis.hi,
            y0: 0.0,
            y1: 1.0,
            left: label_width,
            top,
            width: WIDTH - label_width - RIGHT,
            height: group_height * self.groups.len().max(1) as f64,
        };
        let mut out = String::new();
        open(&mut out, &self.title, height);
        value_axis(&mut out, &f, &self.value_label);
        for (g, group) in self.groups.iter().enumerate() {
            let y0 = f.top + group_height * g as f64 + 5.0;
            let _ = write!(
                out,
                r#"<text x="{:.1}" y="{:.1}" text-anchor="end" class="bl">{}</text>"#,
                f.left - 6.0,
                y0 + group_height / 2.0,
                escape(&shorten(&group.label, 34))
            );
            for (s, (value, whisker)) in group.values.iter().enumerate() {
                let colour = self.series.get(s).map_or(Colour::Blue, |x| x.1);
                let y = y0 + bar * s as f64;
                if value.is_finite() {
                    let _ = write!(
                        out,
                        r#"<rect x="{:.1}" y="{y:.1}" width="{:.1}" height="{:.1}" fill="{}"/>"#,
                        f.left,
                        (f.px(*value) - f.left).max(0.0),
                        bar - 2.0,
                        colour.css()
                    );
                }
                if let Some((lo, hi)) = whisker {
                    let ym = y + (bar - 2.0) / 2.0;
                    let _ = write!(
                        out,
                        r#"<path d="M{:.1} {ym:.1}H{:.1}M{:.1} {:.1}V{:.1}M{:.1} {:.1}V{:.1}" stroke="black" stroke-width="1"/>"#,
                        f.px(*lo),
                        f.px(*hi),
                        f.px(*lo),
                        ym - 3.0,
                        ym + 3.0,
                        f.px(*hi),
                        ym - 3.0,
                        ym + 3.0
                    );
                }
            }
        }
        for (k, (label, colour)) in self.series.iter().enumerate() {
            let y = TOP + 14.0 * k as f64 - 6.0;
            let _ = write!(
                out,
                r#"<rect x="{:.1}" y="{y:.1}" width="10" height="10" fill="{}"/><text x="{:.1}" y="{:.1}" class="lg">{}</text>"#,
                f.left,
                colour.css(),
                f.left + 14.0,
                y + 9.0,
                escape(label)
            );
        }
        out.push_str("</svg>");
        out
    }
}

/// A bar chart's value axis: grid lines, tick labels below, the axis line and its label.
fn value_axis(out: &mut String, f: &Frame, label: &str) {
    let xt = ticks(f.x0, f.x1, 5);
    let xstep = if xt.len() > 1 { xt[1] - xt[0] } else { 1.0 };
    let bottom = f.top + f.height;
    out.push_str(r#"<g class="ax">"#);
    for v in &xt {
        let px = f.px(*v);
        let _ = write!(
            out,
            r#"<line class="grid" x1="{px:.1}" y1="{}" x2="{px:.1}" y2="{bottom}"/><text x="{px:.1}" y="{}" text-anchor="middle">{}</text>"#,
            f.top,
            bottom + 18.0,
            tick_label(*v, xstep)
        );
    }
    let _ = write!(
        out,
        r#"<line x1="{}" y1="{bottom}" x2="{}" y2="{bottom}"/><text x="{:.1}" y="{:.1}" text-anchor="middle">{}</text></g>"#,
        f.left,
        f.left + f.width,
        f.left + f.width / 2.0,
        bottom + 40.0,
        escape(label)
    );
}

/// `s`, cut to `n` characters with an ellipsis (the full text stays in the table beside the chart).
fn shorten(s: &str, n: usize) -> String {
    if s.chars().count() <= n { s.to_string() } else { format!("{}…", s.chars().take(n - 1).collect::<String>()) }
}

#[cfg(test)]
mod tests {
    use super::{tick_label, ticks};

    #[test]
    fn ticks_are_round_and_cover_the_range() {
        for (lo, hi) in [(0.0, 1.0), (-312.0, 1480.0), (0.0012, 0.0097), (-5.0, -4.2), (3.0e3, 6.8e3)] {
            let t = ticks(lo, hi, 6);
            assert!(t.len() >= 3 && t.len() <= 12, "{lo}..{hi}: {t:?}");
            assert!(t.iter().all(|v| *v >= lo - 1e-12 && *v <= hi + 1e-12), "{lo}..{hi}: {t:?}");
            let step = t[1] - t[0];
            let mantissa = step / 10f64.powf(step.log10().floor());
            assert!([1.0, 2.0, 5.0].iter().any(|m| (mantissa - m).abs() < 1e-9), "{lo}..{hi}: step {step}");
        }
        assert_eq!(tick_label(0.6000000000000001, 0.2), "0.6");
        assert_eq!(tick_label(-0.0, 0.5), "0.0");
        assert_eq!(tick_label(1500.0, 500.0), "1500");
    }
}
