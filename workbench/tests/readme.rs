//! The transcripts of the README and of every page of `docs/` (`docs/cli.md`, the manual, holds
//! most) stay true: every `flarebench` command of a `console` block runs as written (in a temporary directory, one directory per block, commands in order) and its
//! output (standard output, or standard error when there is none) must match the transcript in shape — the same lines, with every number, path and
//! run of spaces left free. A line `…` in a transcript stands for any number of lines.

use crate::common;

use std::path::{Path, PathBuf};

use common::temp_dir;
use flarebench::output::{ToneMap, save_image};
use flarebench_sdk::image::HdrImage;

/// Commands that cannot run here as written, with the reason.
const SKIPPED: [(&str, &str); 1] = [("flarebench edit", "interactive (tested in edit_tmux.rs)")];

/// The user's own files some transcripts name, made in the block's directory first: an HDR
/// scene with two lights (`apply`), a lens file with a broken field (`info`), a light path
/// (`render --frames`) and a dataset sampler (`dataset`).
fn make_fixtures(dir: &Path) {
    let (w, h) = (640, 480);
    let mut scene = HdrImage::new(w, h);
    scene.pixels.fill([0.05, 0.05, 0.05]);
    for (x0, y0, level) in [(365, 259, 6.0e4f32), (247, 55, 2.2e4)] {
        for y in y0..y0 + 4 {
            for x in x0..x0 + 5 {
                scene.pixels[y * w + x] = [level; 3];
            }
        }
    }
    save_image(&scene, &dir.join("scene.exr"), &ToneMap::default()).unwrap();
    std::fs::write(
        dir.join("bad.xml"),
        "<opticalSystem><elements><element><type>lensSpherical</type><radius>abc</radius>\
         <thickness>5</thickness><height>10</height></element></elements></opticalSystem>\n",
    )
    .unwrap();
    std::fs::write(dir.join("path.toml"), LIGHT_PATH).unwrap();
    std::fs::write(dir.join("sampler.toml"), SAMPLER).unwrap();
}

/// The light path of `docs/cli.md` § Sequences.
const LIGHT_PATH: &str = "[[light]]\ninterpolation = \"smooth\"\nkey = [\n  \
    { frame = 1, theta = 2, phi = 60 },\n  { frame = 3, theta = 8, phi = 60, intensity = 2 },\n  \
    { frame = 4, theta = 9, phi = 75 },\n]\n";

/// The sampler of `docs/datasets.md` § A first dataset.
const SAMPLER: &str = "size = [64, 48]\nquality = \"fast\"\nstarburst_texels = 64\n\n[lenses]\n\
    names = [\"heliar-tronnier\", \"double-gauss-50mm\"]\n\
    weights = { \"heliar-tronnier\" = 2 }\n\n[lights]\ncount = [1, 2]\nev = [0, 2]\n";

/// The fewest commands that run here, per document that must have them.
const MIN_CHECKED: [(&str, usize); 2] = [("README.md", 6), ("docs/cli.md", 12)];

/// The documents whose transcripts are checked, relative to the repository root: the README
/// and every Markdown page of `docs/`.
fn documents(root: &Path) -> Vec<PathBuf> {
    let mut docs: Vec<PathBuf> = std::fs::read_dir(root.join("docs"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "md"))
        .map(|p| p.strip_prefix(root).unwrap().to_path_buf())
        .collect();
    docs.sort();
    docs.insert(0, PathBuf::from("README.md"));
    docs
}

struct Transcript {
    /// Line of the command in its document.
    line: usize,
    args: Vec<String>,
    expected: Vec<String>,
}

/// The console blocks' commands, grouped by block.
fn blocks(doc: &str) -> Vec<Vec<Transcript>> {
    let mut out = Vec::new();
    let mut lines = doc.lines().enumerate().peekable();
    while let Some((_, l)) = lines.next() {
        if l.trim() != "```console" {
            continue;
        }
        let mut block: Vec<Transcript> = Vec::new();
        while let Some((n, l)) = lines.next() {
            if l.trim() == "```" {
                break;
            }
            if let Some(cmd) = l.strip_prefix("$ ") {
                let mut cmd = cmd.to_string();
                while cmd.ends_with('\\') {
                    cmd.pop();
                    let (_, next) = lines.next().expect("a continued command goes on");
                    cmd.push(' ');
                    cmd.push_str(next.trim());
                }
                let cmd = cmd.split(" #").next().unwrap_or_default();
                let cmd = cmd.replace("cargo run --release -p flarebench --", "flarebench");
                block.push(Transcript {
                    line: n + 1,
                    args: cmd.split_whitespace().map(str::to_string).collect(),
                    expected: Vec::new(),
                });
            } else if let Some(t) = block.last_mut() {
                t.expected.push(l.to_string());
            }
        }
        out.push(block);
    }
    out
}

/// A line with its numbers as `#`, paths as `<path>` and runs of spaces as one.
fn shape(line: &str) -> String {
    let words: Vec<String> = line
        .split_whitespace()
        .map(|w| {
            if w.contains('/') && w.chars().any(|c| c.is_ascii_alphabetic()) && !w.contains(":/") {
                return "<path>".to_string();
            }
            let mut s = String::new();
            let c: Vec<char> = w.chars().collect();
            let mut i = 0;
            while i < c.len() {
                let sign = (c[i] == '-' || c[i] == '+')
                    && c.get(i + 1).is_some_and(char::is_ascii_digit)
                    && (i == 0 || !c[i - 1].is_ascii_alphanumeric());
                if c[i].is_ascii_digit() || sign {
                    i += 1;
                    while i < c.len() {
                        let exp = (c[i] == 'e' || c[i] == 'E')
                            && c.get(i + 1)
                                .is_some_and(|d| d.is_ascii_digit() || *d == '-' || *d == '+');
                        if c[i].is_ascii_digit() || c[i] == '.' {
                            i += 1;
                        } else if exp {
                            i += 2;
                        } else {
                            break;
                        }
                    }
                    s.push('#');
                } else {
                    s.push(c[i]);
                    i += 1;
                }
            }
            s
        })
        .collect();
    words.join(" ")
}

/// Whether `actual` matches `expected` in shape, `…` lines matching any run of lines.
fn matches(expected: &[String], actual: &[String]) -> bool {
    match expected.split_first() {
        None => actual.is_empty(),
        Some((e, rest)) if e.trim() == "…" => {
            (0..=actual.len()).any(|k| matches(rest, &actual[k..]))
        }
        Some((e, rest)) => {
            actual.first().is_some_and(|a| shape(a) == shape(e)) && matches(rest, &actual[1..])
        }
    }
}

#[test]
fn the_transcripts_of_the_readme_and_docs_match_the_binary_in_shape() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let mut checked: Vec<(String, usize)> = Vec::new();
    let mut failures = Vec::new();
    for doc in documents(&root) {
        let name = doc.to_string_lossy().replace('\\', "/");
        let text = std::fs::read_to_string(root.join(&doc)).unwrap();
        let mut count = 0;
        for block in blocks(&text) {
            let tmp = temp_dir("readme");
            make_fixtures(tmp.path());
            for t in block {
                let cmd = t.args.join(" ");
                if t.args.first().map(String::as_str) != Some("flarebench")
                    || SKIPPED.iter().any(|(s, _)| cmd.contains(s))
                {
                    continue;
                }
                let out = common::command()
                    .args(&t.args[1..])
                    .current_dir(tmp.path())
                    .output()
                    .unwrap();
                // Standard output; standard error for a command that reports there
                // (`precompute`) and prints nothing on standard output.
                let stream = if out.stdout.is_empty() {
                    &out.stderr
                } else {
                    &out.stdout
                };
                let actual: Vec<String> = String::from_utf8_lossy(stream)
                    .lines()
                    .map(str::to_string)
                    .collect();
                if !matches(&t.expected, &actual) {
                    failures.push(format!(
                        "{name}:{} `{cmd}`\n--- transcript\n{}\n--- output\n{}\n--- stderr\n{}",
                        t.line,
                        t.expected.join("\n"),
                        actual.join("\n"),
                        String::from_utf8_lossy(&out.stderr)
                    ));
                }
                count += 1;
            }
        }
        checked.push((name, count));
    }
    assert!(failures.is_empty(), "{}", failures.join("\n\n"));
    for (doc, least) in MIN_CHECKED {
        let n = checked
            .iter()
            .find(|(d, _)| d == doc)
            .map_or(0, |(_, n)| *n);
        assert!(
            n >= least,
            "{doc}: {n} commands checked, at least {least} expected"
        );
    }
}

#[test]
fn the_shape_frees_numbers_and_paths_but_not_words() {
    assert_eq!(
        shape("  ghost    7-6: energy 2.699e-4, grid 17², drawn at 1/4"),
        shape("ghost 3-2: energy 3.086e-4, grid 13², drawn at 1/1")
    );
    assert_eq!(shape("error -0.141% (/a/b.xml)"), "error #% <path>");
    assert_ne!(
        shape("starburst of light 0: left out (off frame)"),
        shape("starburst of light 0 at pixel (53.8, 30.6)")
    );
    let e = |v: &[&str]| v.iter().map(|s| s.to_string()).collect::<Vec<_>>();
    assert!(matches(&e(&["a 1", "…", "z"]), &e(&["a 2", "b", "c", "z"])));
    assert!(!matches(&e(&["a 1", "z"]), &e(&["a 2", "b", "z"])));
}
