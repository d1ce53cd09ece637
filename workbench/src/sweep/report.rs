//! The sweep's files: `results.csv` (a row per cell), `per_ghost.csv` (a row per cell and
//! ghost), `results.json` (everything) and `index.html`, which ties the plots, tables and
//! contact sheets together and opens offline (no script, no remote resource).

use std::fmt::Write as _;

use super::{CaseResult, CellResult};

/// A CSV field: quoted when it holds a comma, quote or line break.
fn csv(s: &str) -> String {
    if s.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

fn opt(v: Option<f64>) -> String {
    v.map_or(String::new(), |v| format!("{v}"))
}

/// `results.csv`.
pub fn results_csv(cases: &[CaseResult]) -> String {
    let mut s = String::from(
        "lens,theta_deg,phi_deg,width,height,aperture,series,label,algo,backend,runs,median_ms,min_ms,max_ms,plan_ms,render_ms,relative_rmse,relative_l1,energy_error,ghosts_drawn,ghosts_total,dropped_energy_estimated,dropped_energy_measured,pareto,failure,params\n",
    );
    for case in cases {
        let front = case.pareto();
        let k = &case.case;
        for (i, c) in case.cells.iter().enumerate() {
            let _ = writeln!(
                s,
                "{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}",
                csv(&k.lens),
                k.theta_deg,
                k.phi_deg,
                k.width,
                k.height,
                csv(&k.aperture),
                csv(&c.series),
                csv(&c.label),
                csv(&c.algo),
                csv(&c.backend),
                c.times_ms.len(),
                c.median_ms,
                c.min_ms,
                c.max_ms,
                opt(c.plan_ms),
                opt(c.render_ms),
                c.relative_rmse,
                c.relative_l1,
                c.energy_error,
                c.ghosts_drawn,
                c.ghosts_total.map_or(String::new(), |n| n.to_string()),
                opt(c.dropped_energy_estimated),
                opt(c.dropped_energy_measured),
                front.contains(&i),
                csv(c.failure.as_deref().unwrap_or("")),
                csv(&c.params),
            );
        }
    }
    s
}

/// `per_ghost.csv`.
pub fn per_ghost_csv(cases: &[CaseResult]) -> String {
    let mut s = String::from(
        "lens,theta_deg,phi_deg,series,label,ghost,reference_share,drawn,energy_error,centroid_shift_px,size_ratio\n",
    );
    for case in cases {
        let k = &case.case;
        for c in &case.cells {
            for g in &c.ghosts {
                let _ = writeln!(
                    s,
                    "{},{},{},{},{},{},{},{},{},{},{}",
                    csv(&k.lens),
                    k.theta_deg,
                    k.phi_deg,
                    csv(&c.series),
                    csv(&c.label),
                    g.ghost,
                    g.reference_share,
                    g.drawn,
                    g.energy_error,
                    g.centroid_shift_px,
                    g.size_ratio
                );
            }
        }
    }
    s
}

fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

fn pct(v: f64) -> String {
    if v.is_finite() {
        format!("{:.2}%", 100.0 * v)
    } else {
        "—".to_string()
    }
}

/// Ghosts with at least this share of the reference's energy are listed in the page (all of
/// them are in `per_ghost.csv`).
pub const PAGE_GHOST_SHARE: f64 = 1e-3;

/// The worst drawn ghost of a cell among those with at least 1% of the energy: (|energy
/// error|, centroid shift).
pub fn worst_ghost(c: &CellResult) -> Option<(f64, f64)> {
    let big = c
        .ghosts
        .iter()
        .filter(|g| g.drawn && g.reference_share >= 0.01);
    let e = big
        .clone()
        .map(|g| g.energy_error.abs())
        .fold(None, |a: Option<f64>, v| Some(a.map_or(v, |a| a.max(v))))?;
    let d = big.map(|g| g.centroid_shift_px).fold(0.0, f64::max);
    Some((e, d))
}

/// `index.html`. `command` is the command line that made the sweep; `took_s` how long it ran.
pub fn index_html(cases: &[CaseResult], command: &str, took_s: f64, date: &str) -> String {
    let mut h = String::new();
    h.push_str(
        "<!doctype html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>flarebench sweep</title>\n<style>\nbody{font-family:sans-serif;margin:1.5em;max-width:1400px;color:#222}\ntable{border-collapse:collapse;font-size:13px;margin:.5em 0}\ntd,th{border:1px solid #ccc;padding:2px 6px;text-align:right}\ntd.l,th.l{text-align:left}\ntr.front td{background:#eef6ee;font-weight:bold}\nimg{max-width:100%;border:1px solid #ddd}\ncode{background:#f4f4f4;padding:1px 3px}\ndetails{margin:.2em 0}\n</style></head><body>\n",
    );
    let _ = writeln!(
        h,
        "<h1>flarebench sweep</h1>\n<p><code>{}</code><br>{} · {:.0} s · {} case(s). Error: the image against the reference renderer at the same size (ghosts only). Time: median frame (plan + render) over the timed runs, bars from fastest to slowest. Rows in green are on the Pareto front (nothing else both faster and more accurate). Files: <a href=\"results.csv\">results.csv</a>, <a href=\"per_ghost.csv\">per_ghost.csv</a>, <a href=\"results.json\">results.json</a>.</p>",
        esc(command),
        esc(date),
        took_s,
        cases.len()
    );
    for case in cases {
        let slug = case.case.slug();
        let front = case.pareto();
        let _ = writeln!(
            h,
            "<h2 id=\"{slug}\">{}</h2>\n<p>Reference: {} ghosts with light, rendered in {:.1} s.</p>\n<a href=\"plot-{slug}.svg\"><img src=\"plot-{slug}.png\" alt=\"error against time, {}\"></a>",
            esc(&case.case.title()),
            case.reference
                .ghosts
                .iter()
                .filter(|g| g.1.energy > 0.0)
                .count(),
            case.reference.render_ms / 1e3,
            esc(&case.case.title()),
        );
        h.push_str("<table><tr><th class=\"l\">series</th><th class=\"l\">point</th><th>median ms</th><th>min–max ms</th><th>plan ms</th><th>render ms</th><th>rel RMSE</th><th>rel L1</th><th>energy</th><th>ghosts</th><th>dropped (plan / measured)</th><th>worst ghost ≥1%: energy, shift px</th></tr>\n");
        for (i, c) in case.cells.iter().enumerate() {
            if let Some(f) = &c.failure {
                let _ = writeln!(
                    h,
                    "<tr><td class=\"l\">{}</td><td class=\"l\">{}</td><td class=\"l\" colspan=\"10\">failed: {}</td></tr>",
                    esc(&c.series),
                    esc(&c.label),
                    esc(f)
                );
                continue;
            }
            let ms = |v: Option<f64>| v.map_or("—".to_string(), |v| format!("{v:.1}"));
            let _ = writeln!(
                h,
                "<tr{}><td class=\"l\">{}</td><td class=\"l\">{}</td><td>{:.1}</td><td>{:.1}–{:.1}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{} / {}</td><td>{}</td></tr>",
                if front.contains(&i) {
                    " class=\"front\""
                } else {
                    ""
                },
                esc(&c.series),
                esc(&c.label),
                c.median_ms,
                c.min_ms,
                c.max_ms,
                ms(c.plan_ms),
                ms(c.render_ms),
                pct(c.relative_rmse),
                pct(c.relative_l1),
                pct(c.energy_error),
                match c.ghosts_total {
                    Some(t) => format!("{}/{t}", c.ghosts_drawn),
                    None => c.ghosts_drawn.to_string(),
                },
                c.dropped_energy_estimated.map_or("—".to_string(), pct),
                c.dropped_energy_measured.map_or("—".to_string(), pct),
                worst_ghost(c).map_or("—".to_string(), |(e, d)| format!("{} · {d:.2}", pct(e))),
            );
        }
        h.push_str("</table>\n");
        let _ = writeln!(
            h,
            "<p>Contact sheet (every image at the reference's exposure; * marks the Pareto front):</p>\n<a href=\"contact-{slug}.png\"><img src=\"contact-{slug}.png\" alt=\"contact sheet, {}\"></a>",
            esc(&case.case.title())
        );
        h.push_str("<h3>Ghost by ghost</h3>\n<p>Ghosts with at least 0.1% of the reference's energy; every ghost is in per_ghost.csv.</p>\n");
        for c in case.cells.iter().filter(|c| !c.ghosts.is_empty()) {
            let _ = writeln!(
                h,
                "<details><summary>{} · {}</summary><table><tr><th class=\"l\">ghost</th><th>share</th><th>energy</th><th>centroid shift px</th><th>size ratio</th></tr>",
                esc(&c.series),
                esc(&c.label)
            );
            let mut gs: Vec<_> = c
                .ghosts
                .iter()
                .filter(|g| g.reference_share >= PAGE_GHOST_SHARE)
                .collect();
            gs.sort_by(|a, b| b.reference_share.total_cmp(&a.reference_share));
            for g in gs {
                if g.drawn {
                    let _ = writeln!(
                        h,
                        "<tr><td class=\"l\">{}</td><td>{}</td><td>{}</td><td>{:.3}</td><td>{:.4}</td></tr>",
                        g.ghost,
                        pct(g.reference_share),
                        pct(g.energy_error),
                        g.centroid_shift_px,
                        g.size_ratio
                    );
                } else {
                    let _ = writeln!(
                        h,
                        "<tr><td class=\"l\">{}</td><td>{}</td><td colspan=\"3\" class=\"l\">left out</td></tr>",
                        g.ghost,
                        pct(g.reference_share)
                    );
                }
            }
            h.push_str("</table></details>\n");
        }
    }
    h.push_str("</body></html>\n");
    h
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn csv_fields_are_quoted_when_needed() {
        assert_eq!(csv("a"), "a");
        assert_eq!(csv("a:k=1,j=2"), "\"a:k=1,j=2\"");
        assert_eq!(csv("say \"x\""), "\"say \"\"x\"\"\"");
    }

    #[test]
    fn html_text_is_escaped() {
        assert_eq!(esc("<a & \"b\">"), "&lt;a &amp; &quot;b&quot;&gt;");
    }
}
