//! The f-number a `.lens` file states. The format has no field for it; the library's files
//! say it in their comment header (the Optical Bench converter ends it with
//! `# 18 surfaces, 9 glass elements, f/1.4`), in the `name:` (`… 85mm f/1.4D IF`) and in the
//! file name (`Canon_50mm_F2.88_…`). Read in that order: the last `f/N` of the comment header
//! (the prescription's own, after a zoom's nominal range in its title), else the first `f/N`
//! or `fN` of the name, else of the file name.

/// An f-number a file states, and where it says so ("comment header", "name", "file name").
pub(super) type Stated = (f64, &'static str);

/// The stated f-number and where it was found.
pub(super) fn stated(comments: &[String], name: &str, file_name: &str) -> Option<Stated> {
    let header = comments
        .iter()
        .rev()
        .find_map(|c| f_numbers(c, true).last().copied());
    header
        .map(|n| (n, "comment header"))
        .or_else(|| f_numbers(name, false).first().map(|&n| (n, "name")))
        .or_else(|| {
            f_numbers(file_name, false)
                .first()
                .map(|&n| (n, "file name"))
        })
}

/// Every f-number written in `s`: an `f` or `F` that starts a word (or follows `mm`, as in
/// `XF16mmF1.4`), then `/` (required when `slash`), then a positive number below 100 that is
/// not followed by `mm` (`F100mm` is a focal length).
fn f_numbers(s: &str, slash: bool) -> Vec<f64> {
    let b = s.as_bytes();
    let mut out = Vec::new();
    for i in 0..b.len() {
        if !b[i].eq_ignore_ascii_case(&b'f') {
            continue;
        }
        let starts_word = i == 0
            || !b[i - 1].is_ascii_alphanumeric()
            || (i >= 2 && b[i - 2..i].eq_ignore_ascii_case(b"mm"));
        if !starts_word {
            continue;
        }
        let mut j = i + 1;
        if b.get(j) == Some(&b'/') {
            j += 1;
        } else if slash {
            continue;
        }
        let start = j;
        while j < b.len() && (b[j].is_ascii_digit() || b[j] == b'.') {
            j += 1;
        }
        let digits = s[start..j].trim_end_matches('.');
        if !digits.starts_with(|c: char| c.is_ascii_digit())
            || b.get(j..j + 2)
                .is_some_and(|u| u.eq_ignore_ascii_case(b"mm"))
        {
            continue;
        }
        if let Ok(n) = digits.parse::<f64>()
            && n > 0.0
            && n < 100.0
        {
            out.push(n);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn f_numbers_are_found_where_the_library_writes_them() {
        assert_eq!(f_numbers("Nikon AF Nikkor 85mm f/1.4D IF", true), [1.4]);
        assert_eq!(
            f_numbers("18 surfaces, 9 glass elements, f/1.4", true),
            [1.4]
        );
        assert_eq!(f_numbers("Zoom 24-120mm f/3.5-5.6D", true), [3.5]);
        assert_eq!(f_numbers("Canon EF100mm f2.8L Macro", false), [2.8]);
        assert_eq!(f_numbers("Canon_50mm_F2.88_TS_macro_(x)", false), [2.88]);
        assert_eq!(f_numbers("Fujinon XF16mmF1.4 R", false), [1.4]);
        // Not f-numbers: a focal length, a word, a T-stop, an Optical Bench address.
        assert!(f_numbers("Canon EF100mm", false).is_empty());
        assert!(f_numbers("F100mm", false).is_empty());
        assert!(f_numbers("of 2 photonstophotos T/1.3", false).is_empty());
        assert!(f_numbers("f2.8", true).is_empty());
    }

    #[test]
    fn the_comment_header_comes_first_and_its_last_f_number_wins() {
        let header = vec![
            "Nikon AI AF Nikkor 24-120mm f/3.5-5.6D".to_string(),
            "Patent: US005930051".to_string(),
            "22 surfaces, 13 glass elements, f/4.1".to_string(),
        ];
        assert_eq!(
            stated(&header, "Nikon f/3.5", "x_F2.lens"),
            Some((4.1, "comment header"))
        );
        assert_eq!(
            stated(&[], "Nikon 24-120mm f/3.5-5.6D", "x_F2.lens"),
            Some((3.5, "name"))
        );
        assert_eq!(stated(&[], "Nikon", "x_F2.lens"), Some((2.0, "file name")));
        assert_eq!(stated(&[], "Nikon", "x.lens"), None);
    }
}
