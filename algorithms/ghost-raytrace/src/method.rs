//! How each ghost is drawn: the per-ghost cost and error model, and the choice.
//!
//! Two ways to draw a traced ghost ([`DrawMethod`]): **mesh** — its triangles rasterized, the
//! small ones with exact coverage — and **splat** — band by band, its triangles under a
//! quarter pixel each added as one box of its area (`flarebench_sdk::ghost::splat`). Both
//! carry exactly the ghost's flux; splatting shares a triangle's light between the pixels it
//! straddles by its box rather than its shape, and costs a few multiply-adds a triangle where
//! exact coverage clips polygons against every pixel a triangle touches.
//!
//! For every ghost the plan predicts ([`MethodPrediction`]) each method's time from the
//! ghost's triangle count and mean triangle area on its drawn frame, and the error splatting
//! adds to the frame: the ghost's own relative RMSE splatted ([`splat_error`]) times its
//! share of the frame's squared signal. Both are fitted to measurements
//! (`examples/method_by_ghost.rs`; figures in docs/performance.md). Then ([`choose`]) the
//! ghosts whose splat is predicted cheaper are splatted, the most time saved per error added
//! first, while the frame's predicted added error stays within the preset's budget
//! (`Quality::method_error_budget`, a relative RMSE added in quadrature).

use serde::Serialize;

/// How a ghost is drawn.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum DrawMethod {
    /// Meshed: its triangles rasterized, those under `SAMPLED_MIN_AREA` pixels² with exact
    /// coverage; a dispersive ghost's bands in fringed groups where that pays.
    #[default]
    Mesh,
    /// Splatted: band by band, its triangles under a quarter pixel each added as one box of
    /// its area (`flarebench_sdk::ghost::splat`).
    Splat,
}

impl DrawMethod {
    /// Every method.
    pub const ALL: [DrawMethod; 2] = [DrawMethod::Mesh, DrawMethod::Splat];

    /// The method's name as written on the command line and in reports.
    pub fn name(self) -> &'static str {
        match self {
            DrawMethod::Mesh => "mesh",
            DrawMethod::Splat => "splat",
        }
    }
}

impl std::fmt::Display for DrawMethod {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for DrawMethod {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        DrawMethod::ALL
            .into_iter()
            .find(|m| m.name().eq_ignore_ascii_case(s.trim()))
            .ok_or_else(|| format!("draw method `{s}` is not one of mesh, splat"))
    }
}

/// What the plan predicted of drawing one ghost each way.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct MethodPrediction {
    /// Mean area of the ghost's triangles on its drawn frame (pixels²; its sensor rectangle's
    /// drawn area times [`FILL`] over its triangles).
    pub triangle_px: f64,
    /// Predicted time to draw it meshed and splatted (nanoseconds on one core).
    pub mesh_ns: f64,
    pub splat_ns: f64,
    /// Predicted relative RMSE of the ghost's image splatted against meshed ([`splat_error`]).
    pub splat_error: f64,
    /// Predicted squared relative RMSE splatting adds to the frame: `splat_error²` times the
    /// ghost's share of the frame's Σ (pixel value)².
    pub frame_error2: f64,
}

/// The part of a ghost's sensor rectangle its triangles cover, on average (a ghost's image
/// is about a disc or a ring inside its rectangle).
pub const FILL: f64 = 0.5;

/// Nanoseconds (one core) to trace a grid vertex and make a triangle, either way.
pub const TRIANGLE_NS: f64 = 120.0;

/// Nanoseconds (one core) exact coverage takes for a triangle of `px` pixels² (under
/// `SAMPLED_MIN_AREA`): its setup and clipping, and the pixels it touches.
pub fn exact_ns(px: f64) -> f64 {
    220.0 + 22.0 * px
}

/// Nanoseconds (one core) to splat one triangle as a box (its shade and its box).
pub const BOX_NS: f64 = 28.0;

/// Nanoseconds (one core) per point-sampled pixel of a large triangle (either way).
pub const SAMPLED_PX_NS: f64 = 4.0;

/// Area (pixels²) from which triangles are point-sampled either way
/// (`flarebench_sdk::ghost::mesh::SAMPLED_MIN_AREA`).
const SAMPLED_MIN: f64 = flarebench_sdk::ghost::mesh::SAMPLED_MIN_AREA as f64;

/// Area (pixels²) under which a splatted ghost's triangles are boxes
/// (`flarebench_sdk::ghost::splat::SPLAT_MAX_AREA`).
const SPLAT_MAX: f64 = flarebench_sdk::ghost::splat::SPLAT_MAX_AREA as f64;

/// The predicted relative RMSE of a ghost's image splatted rather than meshed, for a mean
/// triangle area of `px` pixels² (under [`SPLAT_MAX`]; nothing is predicted to change above):
/// a box moves light across a pixel border by up to its own size, which matters most where
/// the ghost is focused within a pixel or two. An envelope above the measurements of the
/// Nikon zoom's ghosts (`examples/method_by_ghost.rs`, light 10°, 30°, 480 × 270 and
/// 960 × 540): 0.4–1.6% at 0.01–0.1 px², and 5.3% for the folded 8-3 at 0.07 px².
pub fn splat_error(px: f64) -> f64 {
    if px >= SPLAT_MAX {
        return 0.0;
    }
    0.02 + 0.13 * px.max(0.0).sqrt()
}

/// The prediction for a ghost of `triangles` triangles a band and `bands` bands over a drawn
/// rectangle of `rect_px` pixels², carrying `signal2_share` of the frame's predicted
/// Σ (pixel value)² ([`signal2`]).
pub fn predict(triangles: f64, bands: usize, rect_px: f64, signal2_share: f64) -> MethodPrediction {
    let per_band = triangles.max(1.0);
    let all = per_band * bands.max(1) as f64;
    let px = FILL * rect_px / per_band;
    let drawn = if px < SAMPLED_MIN {
        exact_ns(px)
    } else {
        SAMPLED_PX_NS * px
    };
    let mesh_ns = all * (TRIANGLE_NS + drawn);
    let (splat_ns, splat_error) = if px < SPLAT_MAX {
        (all * (TRIANGLE_NS + BOX_NS), splat_error(px))
    } else {
        (mesh_ns, 0.0)
    };
    MethodPrediction {
        triangle_px: px,
        mesh_ns,
        splat_ns,
        splat_error,
        frame_error2: splat_error * splat_error * signal2_share,
    }
}

/// A ghost's predicted Σ (pixel value)² on the frame: its on-frame energy spread evenly over
/// [`FILL`] of its drawn rectangle of `rect_px` pixels² (at full resolution).
pub fn signal2(on_frame_energy: f64, rect_px: f64) -> f64 {
    on_frame_energy * on_frame_energy / (FILL * rect_px).max(1.0)
}

/// Each ghost's method, given its prediction: those whose splat is cheaper, most time saved
/// per error added first, splatted while the frame's added squared error stays within
/// `budget²`; the rest meshed.
pub fn choose(predictions: &[MethodPrediction], budget: f64) -> Vec<DrawMethod> {
    let mut methods = vec![DrawMethod::Mesh; predictions.len()];
    let mut order: Vec<usize> = (0..predictions.len())
        .filter(|&i| predictions[i].splat_ns < predictions[i].mesh_ns)
        .collect();
    let gain = |i: usize| {
        let p = &predictions[i];
        (p.mesh_ns - p.splat_ns) / p.frame_error2.max(f64::MIN_POSITIVE)
    };
    order.sort_by(|&a, &b| gain(b).total_cmp(&gain(a)));
    let mut spent = 0.0;
    for i in order {
        let e = predictions[i].frame_error2;
        if spent + e <= budget * budget {
            spent += e;
            methods[i] = DrawMethod::Splat;
        }
    }
    methods
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn small_triangles_are_cheaper_splatted_and_large_ones_the_same() {
        let small = predict(10_000.0, 10, 1_500.0, 0.1);
        assert!(small.triangle_px < 0.25);
        assert!(small.splat_ns < 0.5 * small.mesh_ns, "{small:?}");
        assert!(small.frame_error2 > 0.0);
        let large = predict(1_000.0, 3, 2e4, 0.1);
        assert_eq!(large.mesh_ns, large.splat_ns);
        assert_eq!(large.frame_error2, 0.0);
    }

    #[test]
    fn the_budget_goes_to_the_most_time_saved_per_error() {
        let p = |mesh_ns: f64, splat_ns: f64, frame_error2: f64| MethodPrediction {
            mesh_ns,
            splat_ns,
            frame_error2,
            ..Default::default()
        };
        let ghosts = [
            p(100.0, 10.0, 4e-4),  // 225 000 per unit error
            p(100.0, 10.0, 1e-4),  // 900 000
            p(100.0, 100.0, 0.0),  // nothing to gain
            p(1000.0, 10.0, 9e-4), // 1 100 000
        ];
        // Budget 0.01² = 1e-4... 3.2e-2² = 1.024e-3: 3 and 1 fit (1e-3), 0 does not.
        let m = choose(&ghosts, 3.2e-2);
        use DrawMethod::*;
        assert_eq!(m, vec![Mesh, Splat, Mesh, Splat]);
        // No budget: nothing that adds error is splatted.
        assert_eq!(choose(&ghosts, 0.0), vec![Mesh; 4]);
        // A large one: everything cheaper splatted.
        assert_eq!(choose(&ghosts, 1.0), vec![Splat, Splat, Mesh, Splat]);
    }

    #[test]
    fn names_round_trip() {
        for m in DrawMethod::ALL {
            assert_eq!(m.name().parse::<DrawMethod>(), Ok(m));
        }
        assert!("ray".parse::<DrawMethod>().is_err());
    }
}
