//! `flarebench stability`: the stiff and extreme suite (`crate::stability`) as a table (or
//! JSON) and an exit code: 0 when every figure is within its limit, 1 otherwise.

use anyhow::Context;
use clap::Args;

use crate::lens_library;
use crate::stability::{self, Finding, SuiteOptions};
use crate::table::Table;

#[derive(Debug, Args)]
pub struct StabilityArgs {
    /// Lens files or bundled lens names (default: the 19 lenses at the top of lenses/; the
    /// curated ones in its maker folders are checked by `flarebench curate`).
    pub lenses: Vec<String>,
    /// The quick subset: fewer light angles, 160 px frames, fewer Monte-Carlo rays, no Nikon
    /// zoom Monte-Carlo comparison (what CI runs).
    #[arg(long)]
    pub quick: bool,
    /// Width of the frames ghosts are rendered into (default 160 quick, 320 full).
    #[arg(long)]
    pub width: Option<usize>,
    /// Leave out the synthetic lenses (plate, near-flat, near total internal reflection,
    /// thin air gap, scaled Heliar, Monte-Carlo comparisons): only the lenses' own checks.
    #[arg(long)]
    pub no_synthetic: bool,
    /// Print only the failures and the summary (the JSON holds every finding either way).
    #[arg(long)]
    pub failures_only: bool,
    /// Print one JSON object (every finding) instead of the table.
    #[arg(long)]
    pub json: bool,
    /// Also write the synthetic lenses as flarebench XML into this directory (to look at a
    /// finding with `render`, `crosscheck` or `view`).
    #[arg(long, value_name = "DIR")]
    pub export: Option<std::path::PathBuf>,
}

fn fmt_value(f: &Finding) -> String {
    if f.value.is_nan() {
        "-".into()
    } else if f.value == 0.0 || f.value.fract() == 0.0 && f.value.abs() < 1e6 {
        format!("{}", f.value)
    } else {
        format!("{:.2e}", f.value)
    }
}

pub fn run(args: &StabilityArgs, quiet: bool) -> anyhow::Result<()> {
    if let Some(dir) = &args.export {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
        for lens in stability::synthetic::lenses() {
            let path = dir.join(format!("{}.xml", lens.name));
            std::fs::write(&path, flarebench_sdk::io::write_xml(&lens))
                .with_context(|| format!("writing {}", path.display()))?;
            if !quiet {
                eprintln!("wrote {}", path.display());
            }
        }
    }
    let names = if args.lenses.is_empty() {
        lens_library::core_names()
    } else {
        args.lenses.clone()
    };
    anyhow::ensure!(!names.is_empty(), "no lenses to check");
    let lenses = names
        .iter()
        .map(|n| Ok((n.clone(), lens_library::load(n, true)?.system)))
        .collect::<anyhow::Result<Vec<_>>>()?;
    let mut options = if args.quick {
        SuiteOptions::quick()
    } else {
        SuiteOptions::full()
    };
    options.synthetic = !args.no_synthetic;
    if let Some(w) = args.width {
        anyhow::ensure!(
            (16..=4096).contains(&w),
            "--width must be 16 to 4096, got {w}"
        );
        options.width = w;
    }
    let show = |what: &str| {
        if !quiet && !args.json {
            eprintln!("checking {what}");
        }
    };
    let report = stability::run(&lenses, options, &show);
    if args.json {
        println!(
            "{}",
            serde_json::to_string_pretty(&report).context("writing the report as JSON")?
        );
    } else {
        let mut t = Table::new(&["check", "lens", "case", "value", "limit", "", "what"]);
        for f in report
            .findings
            .iter()
            .filter(|f| !args.failures_only || !f.pass)
        {
            t.row(vec![
                f.check.to_string(),
                f.lens.clone(),
                f.case.clone(),
                fmt_value(f),
                format!("{:.0e}", f.limit),
                if f.pass { "ok" } else { "FAIL" }.to_string(),
                f.note.clone(),
            ]);
        }
        print!("{}", t.render());
        println!(
            "{} findings on {} lenses and the synthetic cases, {} failed ({:.0} s)",
            report.findings.len(),
            lenses.len(),
            report.failed,
            report.seconds
        );
    }
    if report.failed > 0 {
        anyhow::bail!(
            "{} of {} stability findings are outside their limits",
            report.failed,
            report.findings.len()
        );
    }
    Ok(())
}
