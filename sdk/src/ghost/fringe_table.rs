//! A ghost's colour as it accumulates over the dispersion coordinate `τ` ([`FringeTable`]):
//! what the fringe shader ([`super::fringe`]) looks up to colour the open interval of `τ`.

/// Nodes of a [`FringeTable`] over `τ ∈ [0, 1]`.
pub(super) const NODES: usize = 64;

/// A ghost's colour as it accumulates over the dispersion coordinate `τ`: per channel, the
/// share `F(τ)` of the ghost's colour from bins below `τ` (each bin's colour spread evenly over
/// its span of `τ`) and its integral `H(τ) = ∫₀^τ F`, at `NODES + 1` even nodes.
#[derive(Clone, Debug, PartialEq)]
pub struct FringeTable {
    /// `[F_r, F_g, F_b, H_r, H_g, H_b]` at node `i` (`τ = i / NODES`).
    pub(super) nodes: Vec<[f32; 6]>,
    /// The colour's partial moments `M_k(τ) = ∫₀^τ t^k dF(t)` for `k = 1, 2, 3` at node `i`,
    /// `[M_1, M_2, M_3]` per channel (`M_0` is `F`): with them a smoothstep of a linear
    /// function of `τ` integrates exactly against the colour ([`FringeTable::smooth_share`]).
    pub(super) moments: Vec<[[f32; 3]; 3]>,
    /// [`FringeTable::partial_moments`] at 0 and at 1, where a ramp wider than the range
    /// reads them.
    pub(super) ends: [[[f64; 4]; 3]; 2],
}

impl FringeTable {
    /// Number of intervals between the table's nodes (the nodes are at `τ = i / NODE_COUNT`,
    /// `i = 0..=NODE_COUNT`): what a port of the lookups (the GPU backend's) indexes with.
    pub const NODE_COUNT: usize = NODES;

    /// The tabulated values, read-only (for ports of the lookups, e.g. the GPU backend's
    /// `pack_tables`): `NODE_COUNT + 1` nodes, node `i` at `τ = i / NODE_COUNT` holding
    /// `[F_r, F_g, F_b, H_r, H_g, H_b]`, the colour's share `F(τ)` and its integral
    /// `H(τ) = ∫₀^τ F` per channel.
    pub fn nodes(&self) -> &[[f32; 6]] {
        &self.nodes
    }

    /// The table of bins spread evenly over `spans` (`[lo, hi]` within `[0, 1]`, `lo < hi`;
    /// neighbours may overlap) with colours `colours` (per bin, any sign); `None` when a
    /// channel's total is too small against the others' to be split into shares.
    pub fn new(spans: &[[f64; 2]], colours: &[[f64; 3]]) -> Option<FringeTable> {
        if spans.len() != colours.len() || colours.is_empty() {
            return None;
        }
        let total: [f64; 3] = std::array::from_fn(|c| colours.iter().map(|k| k[c]).sum());
        let largest = total.iter().fold(0.0_f64, |m, t| m.max(t.abs()));
        if total
            .iter()
            .any(|&t| t.is_nan() || t.abs() < 1e-3 * largest)
            || largest <= 0.0
            || spans
                .iter()
                .any(|s| s[0].is_nan() || s[1].is_nan() || s[0] >= s[1])
        {
            return None;
        }
        let f = |t: f64| -> [f64; 3] {
            let mut acc = [0.0; 3];
            for (s, colour) in spans.iter().zip(colours) {
                let w = ((t - s[0]) / (s[1] - s[0])).clamp(0.0, 1.0);
                for c in 0..3 {
                    acc[c] += w * colour[c] / total[c];
                }
            }
            acc
        };
        let mut nodes = Vec::with_capacity(NODES + 1);
        let mut moments = Vec::with_capacity(NODES + 1);
        let mut h = [0.0_f64; 3];
        let mut m = [[0.0_f64; 3]; 3];
        let mut prev = f(0.0);
        for i in 0..=NODES {
            let t = i as f64 / NODES as f64;
            let fi = f(t);
            if i > 0 {
                // F is linear between nodes once tabulated: H by the trapezoid rule matches
                // the lookup's own integral, and the moments are those of its constant
                // density on the interval.
                let t0 = (i - 1) as f64 / NODES as f64;
                for c in 0..3 {
                    h[c] += 0.5 * (prev[c] + fi[c]) / NODES as f64;
                    let density = (fi[c] - prev[c]) * NODES as f64;
                    for (k, mk) in m[c].iter_mut().enumerate() {
                        let e = k as i32 + 2;
                        *mk += density * (t.powi(e) - t0.powi(e)) / f64::from(e);
                    }
                }
            }
            moments.push(m.map(|mc| mc.map(|v| v as f32)));
            nodes.push([
                fi[0] as f32,
                fi[1] as f32,
                fi[2] as f32,
                h[0] as f32,
                h[1] as f32,
                h[2] as f32,
            ]);
            prev = fi;
        }
        let mut table = FringeTable {
            nodes,
            moments,
            ends: [[[0.0; 4]; 3]; 2],
        };
        table.ends = [table.partial_moments(0.0), table.partial_moments(1.0)];
        Some(table)
    }

    /// Per channel, `M_k(τ) = ∫₀^τ t^k dF(t)` for `k = 0..=3` (`τ` clamped to `[0, 1]`), from
    /// the tabulated density, constant between nodes.
    #[inline]
    pub(super) fn partial_moments(&self, t: f32) -> [[f64; 4]; 3] {
        let t = f64::from(t.clamp(0.0, 1.0));
        let x = t * NODES as f64;
        let i = (x as usize).min(NODES - 1);
        let t0 = i as f64 / NODES as f64;
        let (a, b, m) = (&self.nodes[i], &self.nodes[i + 1], &self.moments[i]);
        // ∫_{t0}^{t} s^k ds for k = 0..=3.
        let (mut p, mut p0) = (t, t0);
        let mut powers = [0.0_f64; 4];
        for (k, v) in powers.iter_mut().enumerate() {
            *v = (p - p0) / (k + 1) as f64;
            p *= t;
            p0 *= t0;
        }
        std::array::from_fn(|c| {
            let density = f64::from(b[c] - a[c]) * NODES as f64;
            [
                f64::from(a[c]) + density * powers[0],
                f64::from(m[c][0]) + density * powers[1],
                f64::from(m[c][1]) + density * powers[2],
                f64::from(m[c][2]) + density * powers[3],
            ]
        })
    }

    /// `∫₀¹ S(p + q τ) dF(τ)` per channel, exactly (up to the table's f32 values), where `S` is
    /// the smoothstep `3t² − 2t³` of `t` clamped to `[0, 1]` and `q ≠ 0`: the cubic against
    /// the partial moments where `0 < t < 1`, the colour's share where `t ≥ 1`. For ramps
    /// over much of `τ`'s range (`|q|` up to a few), where the moments' differences are well
    /// conditioned.
    pub(super) fn smooth_share(&self, p: f64, q: f64) -> [f32; 3] {
        let (zero, one) = ((-p / q).clamp(0.0, 1.0), ((1.0 - p) / q).clamp(0.0, 1.0));
        // Wholly open where t ≥ 1: above `one` for a rising t, below it for a falling one.
        let f_one = self.share(one as f32);
        let mut out: [f64; 3] = std::array::from_fn(|c| {
            if q > 0.0 {
                1.0 - f64::from(f_one[c])
            } else {
                f64::from(f_one[c])
            }
        });
        let (lo, hi) = (zero.min(one), zero.max(one));
        if hi > lo {
            // 3t² − 2t³ with t = p + qτ, as a cubic in τ.
            let coef = [
                3.0 * p * p - 2.0 * p * p * p,
                6.0 * p * q - 6.0 * p * p * q,
                3.0 * q * q - 6.0 * p * q * q,
                -2.0 * q * q * q,
            ];
            // (The moments at the range's ends are the table's own.)
            let at = |t: f64| {
                if t <= 0.0 {
                    self.ends[0]
                } else if t >= 1.0 {
                    self.ends[1]
                } else {
                    self.partial_moments(t as f32)
                }
            };
            let (ml, mh) = (at(lo), at(hi));
            for ((o, h), l) in out.iter_mut().zip(&mh).zip(&ml) {
                *o += coef[0] * (h[0] - l[0])
                    + coef[1] * (h[1] - l[1])
                    + coef[2] * (h[2] - l[2])
                    + coef[3] * (h[3] - l[3]);
            }
        }
        out.map(|v| v as f32)
    }

    /// `F(τ)`, 0 below the range and 1 above it.
    #[inline]
    pub(super) fn share(&self, t: f32) -> [f32; 3] {
        if t.is_nan() || t <= 0.0 {
            return [0.0; 3];
        }
        if t >= 1.0 {
            return [1.0; 3];
        }
        let x = t * NODES as f32;
        let i = (x as usize).min(NODES - 1);
        let s = x - i as f32;
        let (a, b) = (&self.nodes[i], &self.nodes[i + 1]);
        std::array::from_fn(|c| a[c] + s * (b[c] - a[c]))
    }

    /// `H(τ) = ∫₀^τ F`.
    #[inline]
    pub(super) fn integral(&self, t: f32) -> [f32; 3] {
        if t.is_nan() || t <= 0.0 {
            return [0.0; 3];
        }
        if t >= 1.0 {
            let end = &self.nodes[NODES];
            let over = t - 1.0;
            return [end[3] + over, end[4] + over, end[5] + over];
        }
        let x = t * NODES as f32;
        let i = (x as usize).min(NODES - 1);
        let s = x - i as f32;
        let (a, b) = (&self.nodes[i], &self.nodes[i + 1]);
        let h = 1.0 / NODES as f32;
        std::array::from_fn(|c| a[3 + c] + h * s * (a[c] + 0.5 * s * (b[c] - a[c])))
    }

    /// The mean of `F` over `[a, b]` (`a ≤ b`).
    #[inline]
    pub(super) fn mean_share(&self, a: f32, b: f32) -> [f32; 3] {
        if b <= 0.0 {
            return [0.0; 3];
        }
        if a >= 1.0 {
            return [1.0; 3];
        }
        let w = b - a;
        if w.is_nan() || w <= 1e-5 {
            return self.share(0.5 * (a + b));
        }
        let (ha, hb) = (self.integral(a), self.integral(b));
        std::array::from_fn(|c| (hb[c] - ha[c]) / w)
    }
}
