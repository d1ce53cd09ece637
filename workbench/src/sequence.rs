//! Numbered frame sequences (`render --frames A..B --light-path FILE -o out.####.exr`,
//! `apply plate.####.exr --frames A..B -o out.####.exr`): the frame range, the share of it
//! one process renders (`--shard I/N`), and the file pattern whose `####` (or printf-style
//! `%04d`) becomes the frame number.

use std::path::{Path, PathBuf};

use anyhow::{bail, ensure};
use indicatif::{ProgressBar, ProgressStyle};

/// Frames `first..=last`, both ends included (as the `..` ranges of `flarebench lenses`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FrameRange {
    pub first: u64,
    pub last: u64,
}

impl FrameRange {
    /// Parses `A..B` (both included, `A ≤ B`) or one frame `A`; frames are whole numbers ≥ 0.
    pub fn parse(s: &str) -> Result<FrameRange, String> {
        let num = |t: &str| {
            t.trim().parse::<u64>().map_err(|_| {
                format!("--frames `{s}`: `{t}` is not a frame number (give `A..B`, both included, or `A`)")
            })
        };
        let (first, last) = match s.split_once("..") {
            Some((a, b)) => (num(a)?, num(b)?),
            None => (num(s)?, num(s)?),
        };
        if first > last {
            return Err(format!("--frames `{s}`: the range is empty"));
        }
        Ok(FrameRange { first, last })
    }

    /// Number of frames.
    pub fn len(&self) -> u64 {
        self.last - self.first + 1
    }

    /// Never: a range holds at least one frame.
    pub fn is_empty(&self) -> bool {
        false
    }

    /// Every frame, in order.
    pub fn frames(self) -> std::ops::RangeInclusive<u64> {
        self.first..=self.last
    }
}

/// The part of a sequence one process renders: frames with `(frame − A) % count == index`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Shard {
    pub index: u64,
    pub count: u64,
}

impl Shard {
    /// The whole sequence.
    pub const ALL: Shard = Shard { index: 0, count: 1 };

    /// Parses `I/N` (`0 ≤ I < N`).
    pub fn parse(s: &str) -> Result<Shard, String> {
        let bad = || format!("--shard `{s}` is not I/N with 0 ≤ I < N (e.g. 0/4)");
        let (i, n) = s.split_once('/').ok_or_else(bad)?;
        let index: u64 = i.trim().parse().map_err(|_| bad())?;
        let count: u64 = n.trim().parse().map_err(|_| bad())?;
        if count == 0 || index >= count {
            return Err(bad());
        }
        Ok(Shard { index, count })
    }

    /// The frames of `range` this shard renders.
    pub fn frames(self, range: FrameRange) -> impl Iterator<Item = u64> {
        range
            .frames()
            .filter(move |f| (f - range.first) % self.count == self.index)
    }
}

/// An output path with one frame-number placeholder: a run of `#` (as many digits, zero
/// padded) or `%0Nd` / `%d`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct FramePattern {
    prefix: String,
    digits: usize,
    suffix: String,
}

impl FramePattern {
    /// Finds the placeholder in the output path `path`'s file name.
    pub fn parse(path: &Path) -> anyhow::Result<FramePattern> {
        FramePattern::parse_as(path, "output")
    }

    /// Finds the placeholder in `path`'s file name; errors call the path `what` (`output`,
    /// `image`).
    pub fn parse_as(path: &Path, what: &str) -> anyhow::Result<FramePattern> {
        let s = path
            .to_str()
            .ok_or_else(|| anyhow::anyhow!("the {what} `{}` is not UTF-8", path.display()))?;
        let name_at = s.rfind('/').map_or(0, |i| i + 1);
        let name = &s[name_at..];
        let hashes = name.find('#').map(|i| {
            let n = name[i..].chars().take_while(|&c| c == '#').count();
            (i, n, n)
        });
        let printf = name.find('%').and_then(|i| {
            let rest = &name[i + 1..];
            let digits: String = rest.chars().take_while(char::is_ascii_digit).collect();
            rest[digits.len()..]
                .starts_with('d')
                .then(|| (i, digits.len() + 2, digits.parse::<usize>().unwrap_or(0)))
        });
        let (at, len, digits) = match (hashes, printf) {
            (Some(h), None) => h,
            (None, Some(p)) => p,
            (Some(_), Some(_)) => {
                bail!("the {what} `{s}` has both `#` and `%d`: give one frame-number placeholder")
            }
            (None, None) => bail!(
                "the {what} `{s}` has no frame number: with --frames give a pattern such as \
                 `name.####.exr` or `name.%04d.exr`"
            ),
        };
        let suffix = &name[at + len..];
        ensure!(
            !suffix.contains('#') && !suffix.contains('%'),
            "the {what} `{s}` has more than one frame-number placeholder"
        );
        Ok(FramePattern {
            prefix: format!("{}{}", &s[..name_at], &name[..at]),
            digits,
            suffix: suffix.to_string(),
        })
    }

    /// The path of `frame`.
    pub fn path(&self, frame: u64) -> PathBuf {
        PathBuf::from(format!(
            "{}{frame:0width$}{}",
            self.prefix,
            self.suffix,
            width = self.digits
        ))
    }
}

/// The lowest exposure (EV) `exposure_of` gives over `range`'s frames, and its frame: the one
/// exposure a whole sequence is tone-mapped with, so its brightest frame does not clip.
pub fn darkest_exposure(
    range: FrameRange,
    bar: ProgressBar,
    mut exposure_of: impl FnMut(u64) -> anyhow::Result<f32>,
) -> anyhow::Result<(f32, u64)> {
    let mut best: Option<(f32, u64)> = None;
    for f in range.frames() {
        let ev = exposure_of(f)?;
        if best.is_none_or(|(b, _)| ev < b) {
            best = Some((ev, f));
        }
        bar.inc(1);
    }
    bar.finish_and_clear();
    Ok(best.expect("a range holds a frame"))
}

/// A sequence's progress bar over `len` frames, labelled `msg` (hidden when `quiet`).
pub fn frames_bar(quiet: bool, len: u64, msg: &'static str) -> ProgressBar {
    if quiet {
        return ProgressBar::hidden();
    }
    ProgressBar::new(len)
        .with_style(
            ProgressStyle::with_template(
                "{msg:9} [{bar:30}] {pos}/{len} frames, {elapsed} (eta {eta})",
            )
            .expect("valid template")
            .progress_chars("=> "),
        )
        .with_message(msg)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ranges_include_both_ends() {
        let r = FrameRange::parse("1..5").unwrap();
        assert_eq!(r.frames().collect::<Vec<_>>(), [1, 2, 3, 4, 5]);
        assert_eq!(FrameRange::parse("7").unwrap().len(), 1);
        assert!(FrameRange::parse("5..1").is_err());
        assert!(FrameRange::parse("..3").is_err());
    }

    #[test]
    fn shards_split_the_frames_without_overlap() {
        let r = FrameRange::parse("3..12").unwrap();
        let mut all: Vec<u64> = (0..3)
            .flat_map(|i| Shard { index: i, count: 3 }.frames(r))
            .collect();
        all.sort();
        assert_eq!(all, r.frames().collect::<Vec<_>>());
        assert_eq!(
            Shard::parse("1/3").unwrap().frames(r).collect::<Vec<_>>(),
            [4, 7, 10]
        );
        for bad in ["3/3", "1", "a/2", "0/0"] {
            assert!(Shard::parse(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn patterns_number_frames() {
        let p = FramePattern::parse(Path::new("dir.v2/out.####.exr")).unwrap();
        assert_eq!(p.path(7), PathBuf::from("dir.v2/out.0007.exr"));
        assert_eq!(p.path(123456), PathBuf::from("dir.v2/out.123456.exr"));
        let p = FramePattern::parse(Path::new("f_%03d.png")).unwrap();
        assert_eq!(p.path(5), PathBuf::from("f_005.png"));
        let p = FramePattern::parse(Path::new("f%d.png")).unwrap();
        assert_eq!(p.path(5), PathBuf::from("f5.png"));
        for bad in ["out.exr", "a.##.#.exr", "a.#.%02d.exr"] {
            assert!(FramePattern::parse(Path::new(bad)).is_err(), "{bad}");
        }
    }
}
