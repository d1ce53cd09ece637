//! The Pareto front of (time, error) points: those no other point beats on both.

/// Indices of the points on the Pareto front of `(time, error)`, fastest first: no other
/// point is at least as fast and at least as accurate and strictly better in one. Points with
/// a non-finite coordinate are never on it.
pub fn front(points: &[(f64, f64)]) -> Vec<usize> {
    let mut idx: Vec<usize> = (0..points.len())
        .filter(|&i| points[i].0.is_finite() && points[i].1.is_finite())
        .collect();
    // By time, then error: a sweep keeps each point whose error is below every faster one's.
    idx.sort_by(|&a, &b| {
        points[a]
            .0
            .total_cmp(&points[b].0)
            .then(points[a].1.total_cmp(&points[b].1))
    });
    let mut out = Vec::new();
    let mut best = f64::INFINITY;
    for i in idx {
        if points[i].1 < best {
            best = points[i].1;
            out.push(i);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The front by its definition, point against point.
    fn brute(points: &[(f64, f64)]) -> Vec<usize> {
        let ok = |p: (f64, f64)| p.0.is_finite() && p.1.is_finite();
        let mut v: Vec<usize> = (0..points.len())
            .filter(|&i| ok(points[i]))
            .filter(|&i| {
                !(0..points.len()).any(|j| {
                    let (a, b) = (points[j], points[i]);
                    j != i && ok(a) && a.0 <= b.0 && a.1 <= b.1 && (a.0 < b.0 || a.1 < b.1 || j < i)
                })
            })
            .collect();
        v.sort_by(|&a, &b| points[a].0.total_cmp(&points[b].0));
        v
    }

    #[test]
    fn a_small_case_by_hand() {
        let p = [
            (1.0, 0.1),
            (2.0, 0.05),
            (1.5, 0.2),
            (3.0, 0.05),
            (0.5, 1.0),
            (4.0, 0.01),
        ];
        assert_eq!(front(&p), vec![4, 0, 1, 5]);
    }

    #[test]
    fn matches_the_definition_on_many_point_sets() {
        // A fixed pseudo-random sequence (xorshift), with ties and NaNs among the points.
        let mut s: u64 = 0x9e37_79b9_7f4a_7c15;
        let mut next = || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            (s % 20) as f64
        };
        for _ in 0..200 {
            let n = 1 + (next() as usize % 12);
            let mut p: Vec<(f64, f64)> = (0..n).map(|_| (next(), next())).collect();
            if next() < 3.0 {
                p[0].1 = f64::NAN;
            }
            assert_eq!(front(&p), brute(&p), "{p:?}");
        }
    }
}
