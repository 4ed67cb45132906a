//! Reports people look at: a bake's report (`bake --report R.html`) and a
//! batch's merged report as one self-contained HTML page each. Pictures are
//! embedded as base64 PNG, plots as inline SVG; the page loads nothing.

use crate::batch::report::{BatchReport, JobStatus};
use crate::sim::attribute_names::BOND_RATES;
use crate::timeline::plots::PlotSample;
use crate::timeline::report::BakeReport;
use base64::Engine;
use std::fmt::Write;
use std::path::Path;

mod links;
pub use links::relative_href;

/// Text made safe for HTML.
fn escape(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&#39;"),
            c => out.push(c),
        }
    }
    out
}

fn png_data_uri(png: &[u8]) -> String {
    format!(
        "data:image/png;base64,{}",
        base64::engine::general_purpose::STANDARD.encode(png)
    )
}

const STYLE: &str = "body{font:14px/1.4 system-ui,sans-serif;margin:24px;color:#222;background:#fafafa}\
h1{font-size:22px}h2{font-size:17px;margin-top:28px}\
table{border-collapse:collapse;background:#fff}td,th{border:1px solid #ccc;padding:4px 8px;text-align:left;vertical-align:middle}\
th{background:#eee}td.num{text-align:right;font-variant-numeric:tabular-nums}code{font-size:12px}\
.ok{color:#176f2c;font-weight:600}.skipped{color:#2458a6;font-weight:600}.failed,.missing,.interrupted{color:#b00020;font-weight:600}\
.plots{display:flex;flex-wrap:wrap;gap:16px}svg{background:#fff;border:1px solid #ccc}img.sheet{max-width:100%;border:1px solid #ccc}";

fn page(title: &str, body: &str) -> String {
    format!(
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\
<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\
<link rel=\"icon\" href=\"data:,\"><title>{}</title><style>{STYLE}</style></head>\n<body>\n{body}</body></html>\n",
        escape(title)
    )
}

/// One curve of a plot: its name, colour, dash pattern (SVG
/// `stroke-dasharray`, empty for a solid line) and points (x, y).
pub struct Series {
    pub name: String,
    pub color: &'static str,
    pub dash: &'static str,
    pub points: Vec<(f64, f64)>,
}

/// An axis label: three decimals, or three significant digits for small values.
fn axis_number(v: f64) -> String {
    if v != 0.0 && v.abs() < 0.01 {
        format!("{v:.2e}")
    } else {
        format!("{v:.3}")
    }
}

/// A line plot as inline SVG, with its axis ranges labelled and a legend.
pub fn svg_plot(title: &str, x_label: &str, series: &[Series]) -> String {
    // The legend sits right of the plot area, clear of the curves.
    let (w, h, left, right, top, bottom) = (500.0, 240.0, 56.0, 112.0, 28.0, 40.0);
    let all = series
        .iter()
        .flat_map(|s| s.points.iter())
        .filter(|p| p.0.is_finite() && p.1.is_finite());
    let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
    for &(x, y) in all {
        x0 = x0.min(x);
        x1 = x1.max(x);
        y0 = y0.min(y);
        y1 = y1.max(y);
    }
    if x0 > x1 {
        (x0, x1, y0, y1) = (0.0, 1.0, 0.0, 1.0);
    }
    y0 = y0.min(0.0);
    if y1 - y0 < 1e-12 {
        y1 = y0 + 1.0;
    }
    if x1 - x0 < 1e-12 {
        x1 = x0 + 1.0;
    }
    let sx = |x: f64| left + (x - x0) / (x1 - x0) * (w - left - right);
    let sy = |y: f64| h - bottom - (y - y0) / (y1 - y0) * (h - top - bottom);
    let mut svg = String::new();
    let _ = write!(
        svg,
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{w}\" height=\"{h}\" viewBox=\"0 0 {w} {h}\" role=\"img\" aria-label=\"{t}\">\
<text x=\"{left}\" y=\"18\" font-size=\"13\" font-weight=\"600\">{t}</text>\
<line x1=\"{left}\" y1=\"{yb}\" x2=\"{xr}\" y2=\"{yb}\" stroke=\"#444\"/><line x1=\"{left}\" y1=\"{top}\" x2=\"{left}\" y2=\"{yb}\" stroke=\"#444\"/>\
<text x=\"{left}\" y=\"{yl}\" font-size=\"11\">{x0:.2}</text><text x=\"{xr}\" y=\"{yl}\" font-size=\"11\" text-anchor=\"end\">{x1:.2}</text>\
<text x=\"{xm}\" y=\"{yl}\" font-size=\"11\" text-anchor=\"middle\">{xlab}</text>\
<text x=\"{lt}\" y=\"{yb}\" font-size=\"11\" text-anchor=\"end\">{y0s}</text><text x=\"{lt}\" y=\"{ty}\" font-size=\"11\" text-anchor=\"end\">{y1s}</text>",
        t = escape(title),
        yb = h - bottom,
        xr = w - right,
        yl = h - bottom + 16.0,
        xm = (left + w - right) / 2.0,
        xlab = escape(x_label),
        lt = left - 4.0,
        ty = top + 4.0,
        y0s = axis_number(y0),
        y1s = axis_number(y1),
    );
    for (k, s) in series.iter().enumerate() {
        let points: Vec<String> = s
            .points
            .iter()
            .filter(|p| p.0.is_finite() && p.1.is_finite())
            .map(|&(x, y)| format!("{:.1},{:.1}", sx(x), sy(y)))
            .collect();
        // Curves that coincide (bonds intact together) stay told apart by
        // their dashes; the legend draws each dash.
        let dash = if s.dash.is_empty() {
            String::new()
        } else {
            format!(" stroke-dasharray=\"{}\"", s.dash)
        };
        let _ = write!(
            svg,
            "<polyline fill=\"none\" stroke=\"{c}\" stroke-width=\"2\"{dash} points=\"{p}\"/>",
            c = s.color,
            p = points.join(" ")
        );
        // Points only where they are few enough to read as samples.
        if points.len() <= 12 {
            for p in &points {
                if let Some((x, y)) = p.split_once(',') {
                    let _ = write!(
                        svg,
                        "<circle cx=\"{x}\" cy=\"{y}\" r=\"2.5\" fill=\"{}\"/>",
                        s.color
                    );
                }
            }
        }
        let ly = top + 4.0 + 14.0 * k as f64;
        let _ = write!(
            svg,
            "<line x1=\"{lx}\" y1=\"{ry}\" x2=\"{lx2}\" y2=\"{ry}\" stroke=\"{c}\" stroke-width=\"2\"{dash}/><text x=\"{tx}\" y=\"{ly}\" font-size=\"11\">{n}</text>",
            lx = w - right + 4.0,
            lx2 = w - right + 22.0,
            ry = ly - 4.0,
            c = s.color,
            tx = w - right + 26.0,
            n = escape(&s.name)
        );
    }
    svg.push_str("</svg>");
    svg
}

const BOND_COLORS: [&str; 4] = ["#1f77b4", "#d62728", "#2ca02c", "#9467bd"];
/// Hydrogen solid, ionic dashed, disulfide dotted, peptide dash-dot.
const BOND_DASHES: [&str; 4] = ["", "7 4", "2 3", "9 3 2 3"];

/// The plots of a bake: mean bond rates per kind, mean wetness and the
/// largest edge strain (against the groom at the start), sampled every
/// frame (1/24 s) and at the end of every stage ([`PlotSample`]).
fn bake_plots(samples: &[PlotSample]) -> String {
    let bonds: Vec<Series> = BOND_RATES
        .iter()
        .zip(BOND_COLORS.iter().zip(BOND_DASHES))
        .enumerate()
        .map(|(k, (name, (&color, dash)))| Series {
            name: name.trim_start_matches("bond_").to_string(),
            color,
            dash,
            points: samples.iter().map(|s| (s.time, s.bonds[k])).collect(),
        })
        .collect();
    let wetness = [Series {
        name: "wetness".into(),
        color: "#17becf",
        dash: "",
        points: samples.iter().map(|s| (s.time, s.wetness)).collect(),
    }];
    let strain = [Series {
        name: "largest strain".into(),
        color: "#ff7f0e",
        dash: "",
        points: samples.iter().map(|s| (s.time, s.strain)).collect(),
    }];
    format!(
        "<div class=\"plots\">{}{}{}</div>\n",
        svg_plot("Mean bond rate per kind", "time (s)", &bonds),
        svg_plot("Mean wetness", "time (s)", &wetness),
        svg_plot("Largest segment strain", "time (s)", &strain)
    )
}

fn warnings_html(warnings: &[String]) -> String {
    if warnings.is_empty() {
        return "<p>None.</p>\n".into();
    }
    let items: String = warnings
        .iter()
        .map(|w| format!("<li>{}</li>", escape(w)))
        .collect();
    format!("<ul>{items}</ul>\n")
}

/// A path shown as a link relative to the page's folder `page_dir` (the
/// text stays the path as the report has it).
fn link(page_dir: &Path, target: &Path, text: &str) -> String {
    match relative_href(page_dir, target) {
        Some(href) => format!("<a href=\"{}\">{}</a>", escape(&href), escape(text)),
        None => escape(text),
    }
}

/// The HTML page of a bake: facts, contact sheet, stage timings, plots,
/// contained strands, warnings, and the outputs with size and SHA-256,
/// linked relative to `page_dir`, the folder the page is written to.
pub fn bake_page(
    report: &BakeReport,
    samples: &[PlotSample],
    sheet_png: Option<&[u8]>,
    page_dir: &Path,
) -> String {
    let mut body = String::new();
    let _ = write!(
        body,
        "<h1>groombake bake: {}</h1>\n<p>groombake {} &middot; seed {} &middot; {} threads &middot; {} strands, {} vertices &middot; {:.3} s simulated in {:.2} s</p>\n",
        escape(&report.timeline),
        escape(&report.groombake_version),
        report.seed,
        report.threads,
        report.strands,
        report.vertices,
        report.simulated_seconds,
        report.wall_seconds
    );
    body.push_str("<h2>Contact sheet: before and after each stage</h2>\n");
    match sheet_png {
        Some(png) => {
            let _ = writeln!(
                body,
                "<img class=\"sheet\" alt=\"contact sheet\" src=\"{}\">",
                png_data_uri(png)
            );
        }
        None => body.push_str("<p>No sheet.</p>\n"),
    }
    // The hold is shown only where a stage has one (it is off by default).
    let held = report.stages.iter().any(|s| s.hold.is_some());
    let _ = writeln!(
        body,
        "<h2>Stages</h2>\n<table><tr><th>#</th><th>name</th><th>kind</th><th>simulated (s)</th><th>steps</th><th>wall (s)</th><th>set kept</th><th>contained strands</th>{}</tr>",
        if held {
            "<th>hold (1/s<sup>2</sup>, root &rarr; tip)</th>"
        } else {
            ""
        }
    );
    for s in &report.stages {
        let hold = match (held, &s.hold) {
            (false, _) => String::new(),
            (true, None) => "<td>off</td>".to_string(),
            (true, Some(h)) => format!(
                "<td class=\"num\">{} &rarr; {}</td>",
                h.strength * h.ramp[0],
                h.strength * h.ramp[1]
            ),
        };
        let contained = if s.contained_strands.is_empty() {
            "none".to_string()
        } else {
            format!("{} {:?}", s.contained_strands.len(), s.contained_strands)
        };
        let _ = writeln!(
            body,
            "<tr><td class=\"num\">{}</td><td>{}</td><td>{}</td><td class=\"num\">{:.3}</td><td class=\"num\">{}</td><td class=\"num\">{:.3}</td><td class=\"num\">{}</td><td>{}</td>{hold}</tr>",
            s.index,
            escape(&s.name),
            escape(&s.kind),
            s.simulated_seconds,
            s.steps,
            s.wall_seconds,
            s.set_kept
                .map_or_else(|| "&ndash;".to_string(), |k| format!("{:.0} %", k * 100.0)),
            escape(&contained)
        );
    }
    body.push_str("</table>\n<p><small>Set kept: the share of the largest shape change so far (the pose pressed, wound or blown furthest from the groom at the start) that the rest shape keeps: 0 % the hair would spring back to its groomed shape if released after the stage, 100 % it keeps the whole change.</small></p>\n<h2>Over time</h2>\n");
    body.push_str(&bake_plots(samples));
    body.push_str("<h2>Warnings</h2>\n");
    body.push_str(&warnings_html(&report.warnings));
    body.push_str("<h2>Outputs</h2>\n<table><tr><th>path</th><th>what</th><th>frames</th><th>bytes</th><th>SHA-256</th></tr>\n");
    for o in &report.outputs {
        let _ = writeln!(
            body,
            "<tr><td>{}</td><td>{}</td><td class=\"num\">{}</td><td class=\"num\">{}</td><td><code>{}</code></td></tr>",
            link(page_dir, Path::new(&o.path), &o.path),
            escape(&o.what),
            o.frames.map(|f| f.to_string()).unwrap_or_default(),
            o.bytes,
            escape(&o.sha256)
        );
    }
    body.push_str("</table>\n");
    page(&format!("groombake bake: {}", report.timeline), &body)
}

/// The HTML page of a batch: a row per job with a thumbnail of its contact
/// sheet (a `.png` output), its status, time, groom and outputs, linked
/// relative to `page_dir`, the folder the page is written to.
pub fn batch_page(report: &BatchReport, page_dir: &Path) -> String {
    let mut body = String::new();
    // The jobs' own times: a merge of a farm's reports runs long after them.
    let job_seconds: f64 = report.jobs.iter().map(|j| j.wall_seconds).sum();
    let _ = write!(
        body,
        "<h1>groombake batch: {}</h1>\n<p>groombake {} &middot; {} jobs: {} succeeded, {} failed, {} missing &middot; jobs took {:.1} s in all &middot; this run {:.1} s</p>\n",
        escape(&report.manifest),
        escape(&report.groombake_version),
        report.jobs.len(),
        report.succeeded,
        report.failed,
        report.missing,
        job_seconds,
        report.wall_seconds
    );
    body.push_str("<table><tr><th>sheet</th><th>job</th><th>status</th><th>wall (s)</th><th>outputs (bytes, SHA-256)</th></tr>\n");
    for job in &report.jobs {
        let folder = std::path::Path::new(&job.folder);
        let thumbnail = job
            .outputs
            .iter()
            .find(|o| o.path.ends_with(".png"))
            .and_then(|o| std::fs::read(folder.join(&o.path)).ok())
            .map(|png| {
                format!(
                    "<img alt=\"sheet of {}\" width=\"200\" src=\"{}\">",
                    escape(&job.name),
                    png_data_uri(&png)
                )
            })
            .unwrap_or_else(|| "&ndash;".into());
        let groom = job
            .groom
            .as_deref()
            .map(|g| format!("<br>groom {}", escape(g)))
            .unwrap_or_default();
        let status = match job.status {
            JobStatus::Ok => "ok",
            JobStatus::Skipped => "skipped",
            JobStatus::Failed => "failed",
            JobStatus::Missing => "missing",
            JobStatus::Interrupted => "interrupted",
        };
        let error = job
            .error
            .as_deref()
            .map(|e| format!("<br>{}", escape(e)))
            .unwrap_or_default();
        let outputs: String = job
            .outputs
            .iter()
            .map(|o| {
                format!(
                    "{} ({} bytes, <code>{}</code>)<br>",
                    link(page_dir, &folder.join(&o.path), &o.path),
                    o.bytes,
                    escape(&o.sha256[..o.sha256.len().min(16)])
                )
            })
            .collect();
        let _ = writeln!(
            body,
            "<tr><td>{thumbnail}</td><td>{}<br><small>{}{groom}</small></td><td class=\"{status}\">{status}{error}</td><td class=\"num\">{:.2}</td><td>{outputs}</td></tr>",
            escape(&job.name),
            escape(&job.timeline),
            job.wall_seconds
        );
    }
    body.push_str("</table>\n");
    page(&format!("groombake batch: {}", report.manifest), &body)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn text_is_escaped() {
        assert_eq!(
            escape("<a href='x'>&</a>"),
            "&lt;a href=&#39;x&#39;&gt;&amp;&lt;/a&gt;"
        );
    }

    #[test]
    fn plot_has_one_polyline_per_series() {
        let series = [
            Series {
                name: "a".into(),
                color: "#000",
                dash: "",
                points: vec![(0.0, 1.0), (1.0, 2.0)],
            },
            Series {
                name: "b".into(),
                color: "#f00",
                dash: "2 3",
                points: vec![(0.0, 0.5)],
            },
        ];
        let svg = svg_plot("t", "x", &series);
        assert_eq!(svg.matches("<polyline").count(), 2);
        assert_eq!(svg.matches("<circle").count(), 3);
    }
}
