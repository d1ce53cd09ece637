//! Matching a lens name against the bundled library: by exact stem (or `maker/stem`), then a
//! unique prefix, then a unique substring, case-insensitively; when nothing matches, the
//! nearest names (shared words, then edit distance).

use super::BundledLens;

/// Candidates named in an ambiguity error; the rest are counted.
pub const MAX_LISTED: usize = 12;
/// Near names suggested for an unknown one.
const MAX_SUGGESTED: usize = 5;

/// What a name matched.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Found {
    /// One lens (its index in the library).
    One(usize),
    /// Several: how they matched (`a prefix`, `a part`) and their indices, sorted by name.
    Ambiguous(&'static str, Vec<usize>),
    /// None; the nearest names' indices, best first (possibly none).
    None(Vec<usize>),
}

/// A test on a lens's lowercase stem and `maker/stem`.
type NameTest<'a> = &'a dyn Fn(&str, &str) -> bool;

/// Finds `spec` among `lenses`: an exact stem or `maker/stem`, else the lenses whose stem or
/// `maker/stem` starts with it, else those whose `maker/stem` contains it. One lens is a
/// match; several are ambiguous (a prefix shared by several lenses does not fall through to
/// the substring step).
pub fn find(spec: &str, lenses: &[BundledLens]) -> Found {
    let want = spec.trim().to_lowercase();
    if want.is_empty() {
        return Found::None(Vec::new());
    }
    let lower: Vec<(String, String)> = lenses
        .iter()
        .map(|l| (l.name.to_lowercase(), l.qualified.to_lowercase()))
        .collect();
    let matching = |test: &dyn Fn(&str, &str) -> bool| -> Vec<usize> {
        (0..lenses.len())
            .filter(|&i| test(&lower[i].0, &lower[i].1))
            .collect()
    };
    let exact = matching(&|name, qualified| name == want || qualified == want);
    if let [i] = exact[..] {
        return Found::One(i);
    }
    let steps: [(&'static str, NameTest<'_>); 2] = [
        ("a prefix", &|name, qualified| {
            name.starts_with(&want) || qualified.starts_with(&want)
        }),
        ("a part", &|_, qualified| qualified.contains(&want)),
    ];
    for (how, test) in steps {
        match matching(test)[..] {
            [] => continue,
            [i] => return Found::One(i),
            ref several => return Found::Ambiguous(how, several.to_vec()),
        }
    }
    Found::None(nearest(&want, &lower))
}

/// Words shorter than this are left out of the comparison (`f2`, `no`: parts of too many
/// names to mean anything).
const MIN_WORD: usize = 3;

/// The words of a name: its parts between `-`, `_`, `/`, spaces and dots, of at least
/// [`MIN_WORD`] characters.
fn words(s: &str) -> Vec<&str> {
    s.split(['-', '_', '/', ' ', '.'])
        .filter(|w| w.chars().count() >= MIN_WORD)
        .collect()
}

/// The names nearest `want` (lowercase): those sharing the most of its words (a word counts
/// when the name contains it; see [`words`]), then the smallest edit distance to the stem; a name qualifies
/// by a shared word or an edit distance within a third of the name's length.
fn nearest(want: &str, lower: &[(String, String)]) -> Vec<usize> {
    let wanted = words(want);
    let mut scored: Vec<(usize, usize, usize)> = lower
        .iter()
        .enumerate()
        .map(|(i, (name, qualified))| {
            let shared = wanted.iter().filter(|w| qualified.contains(*w)).count();
            (i, shared, strsim::levenshtein(want, name))
        })
        .filter(|&(i, shared, distance)| {
            shared > 0 || distance <= lower[i].0.chars().count().div_ceil(3)
        })
        .collect();
    scored.sort_by(|a, b| b.1.cmp(&a.1).then(a.2.cmp(&b.2)).then(a.0.cmp(&b.0)));
    scored
        .into_iter()
        .take(MAX_SUGGESTED)
        .map(|(i, _, _)| i)
        .collect()
}

#[cfg(test)]
mod tests {
    use std::path::PathBuf;

    use super::*;

    fn library(names: &[&str]) -> Vec<BundledLens> {
        names
            .iter()
            .map(|q| {
                let (folder, name) = match q.split_once('/') {
                    Some((f, n)) => (Some(f.to_string()), n.to_string()),
                    None => (None, q.to_string()),
                };
                BundledLens {
                    name,
                    qualified: q.to_string(),
                    folder,
                    path: PathBuf::from(format!("{q}.xml")),
                }
            })
            .collect()
    }

    const NAMES: &[&str] = &[
        "heliar-tronnier",
        "heliar-tronnier-lff",
        "nikon/ai-nikkor-135mm-f2",
        "nikon/ai-nikkor-180mm-f2.8-ed",
        "canon/ef-16-35mm-f2.8l",
        "zeiss/distagon-35mm-f1.4",
    ];

    #[test]
    fn an_exact_stem_wins_over_longer_names_it_begins() {
        let l = library(NAMES);
        assert_eq!(find("heliar-tronnier", &l), Found::One(0));
        assert_eq!(find("Heliar-Tronnier-LFF", &l), Found::One(1));
        assert_eq!(find("nikon/ai-nikkor-135mm-f2", &l), Found::One(2));
    }

    #[test]
    fn a_unique_prefix_or_part_names_one_lens() {
        let l = library(NAMES);
        assert_eq!(find("ai-nikkor-18", &l), Found::One(3));
        assert_eq!(find("canon/", &l), Found::One(4));
        assert_eq!(find("distagon", &l), Found::One(5));
        assert_eq!(find("16-35", &l), Found::One(4));
    }

    #[test]
    fn an_ambiguous_name_gives_every_candidate_and_how_it_matched() {
        let l = library(NAMES);
        assert_eq!(
            find("ai-nikkor", &l),
            Found::Ambiguous("a prefix", vec![2, 3])
        );
        assert_eq!(find("nikkor", &l), Found::Ambiguous("a part", vec![2, 3]));
        assert_eq!(find("nikon", &l), Found::Ambiguous("a prefix", vec![2, 3]));
    }

    #[test]
    fn an_unknown_name_suggests_the_nearest_ones_only() {
        let l = library(NAMES);
        // A typo: by edit distance.
        assert_eq!(find("helair-tronnier", &l), Found::None(vec![0, 1]));
        // Shared words first.
        match find("nikkor-135-f2", &l) {
            Found::None(near) => assert_eq!(near[0], 2, "{near:?}"),
            other => panic!("{other:?}"),
        }
        assert_eq!(find("leica-summilux", &l), Found::None(vec![]));
        assert_eq!(find("  ", &l), Found::None(vec![]));
    }
}
