//! `flarebench lenses`: the bundled library listed and filtered (`crate::lens_listing`).

use anyhow::Context;
use clap::Args;
use flarebench_sdk::LensKind;

use crate::lens_library;
use crate::lens_listing::{self, Filter, Span, focal_text};
use crate::table::Table;

#[derive(Debug, Args)]
pub struct LensesArgs {
    /// Words each found (case-insensitive) in the lens's name, its maker or its notes.
    pub terms: Vec<String>,
    #[command(flatten)]
    pub filter: FilterArgs,
    /// Print a JSON array instead of the table.
    #[arg(long)]
    pub json: bool,
}

/// The filters of the bundled library, shared by `lenses` and `gallery`.
#[derive(Debug, Default, Args)]
pub struct FilterArgs {
    /// Part of the maker's name, or its folder (`nikon`, `zeiss`).
    #[arg(long)]
    pub maker: Option<String>,
    /// Focal length in mm, a range (`24..35`, `..20`, `300..`) or one value; a zoom matches when
    /// its range overlaps it.
    #[arg(long, value_name = "RANGE")]
    pub focal: Option<String>,
    /// F-number, a range (`..2`, `1.4..2.8`) or one value, as listed (one decimal).
    #[arg(long, value_name = "RANGE")]
    pub fnum: Option<String>,
    /// Kind: prime, zoom, fisheye, macro, cine, tilt-shift (repeat or separate by commas: all
    /// must hold).
    #[arg(long, value_name = "KIND", value_delimiter = ',', value_parser = parse_kind)]
    pub kind: Vec<LensKind>,
}

impl FilterArgs {
    /// True when no filter is given.
    pub fn is_empty(&self) -> bool {
        self.maker.is_none() && self.focal.is_none() && self.fnum.is_none() && self.kind.is_empty()
    }

    /// The filter these options and `terms` (words) ask for.
    pub fn filter(&self, terms: &[String]) -> anyhow::Result<Filter> {
        Ok(Filter {
            maker: self.maker.clone(),
            focal: self
                .focal
                .as_deref()
                .map(|s| Span::parse(s, "--focal"))
                .transpose()?,
            fnum: self
                .fnum
                .as_deref()
                .map(|s| Span::parse(s, "--fnum"))
                .transpose()?,
            kind: self.kind.clone(),
            terms: terms.to_vec(),
        })
    }
}

fn parse_kind(s: &str) -> Result<LensKind, String> {
    LensKind::parse(s).ok_or_else(|| {
        let known: Vec<&str> = LensKind::ALL.iter().map(|k| k.name()).collect();
        format!("unknown kind `{s}`; expected one of {}", known.join(", "))
    })
}

pub fn run(args: &LensesArgs, quiet: bool) -> anyhow::Result<()> {
    let filter = args.filter.filter(&args.terms)?;
    let root = lens_library::library_dirs()
        .into_iter()
        .next()
        .context("no bundled lens library was found")?;
    let bundled = lens_library::bundled();
    let mut listed = Vec::new();
    let mut failed = 0;
    for result in lens_listing::load_all(&bundled, &root) {
        match result {
            Ok(l) => listed.push(l),
            Err(e) => {
                failed += 1;
                eprintln!("warning: {e:#}");
            }
        }
    }
    let total = listed.len();
    listed.retain(|l| filter.matches(l));
    if args.json {
        println!("{}", serde_json::to_string_pretty(&listed)?);
    } else {
        let mut t = Table::new(&[
            "name", "maker", "focal mm", "f/", "kind", "elements", "ghosts",
        ]);
        for l in &listed {
            let kinds: Vec<&str> = l.kind.iter().map(|k| k.name()).collect();
            t.row(vec![
                l.name.clone(),
                if l.maker.is_empty() {
                    "-".into()
                } else {
                    l.maker.clone()
                },
                focal_text(l.focal_mm),
                format!("{:.1}", l.f_number),
                if kinds.is_empty() {
                    "-".into()
                } else {
                    kinds.join(" ")
                },
                l.elements.to_string(),
                l.ghosts.to_string(),
            ]);
        }
        print!("{}", t.render());
        if !quiet {
            println!("{} of {total} bundled lenses", listed.len());
        }
    }
    anyhow::ensure!(
        failed == 0,
        "{failed} bundled lenses could not be read (above)"
    );
    Ok(())
}
