//! The automatic exposure of a flare frame: the stops that bring its brightest lit pixels to
//! white, or — when ghosts are drawn — its ghosts' brightest to a quarter of white, so a light
//! in the frame clips as in a photograph that shows its flare.

use flarebench_sdk::image::HdrImage;

/// Stops the automatic exposure leaves above the brightest 0.1% of the ghosts' pixels: they
/// land at a quarter of white, so ghosts that overlap stay translucent and keep their colour
/// through the tone curve (at 0 the Heliar's ghosts for a light at 8°, 60° wash the frame out).
pub const GHOST_HEADROOM_EV: f32 = -2.0;

/// Exposure (stops) that maps the 99.9th percentile of the lit pixels' luminance to 1;
/// 0 for an empty image.
pub fn auto_exposure(img: &HdrImage) -> f32 {
    lit_exposure(img).unwrap_or(0.0)
}

/// The exposure of a frame whose ghosts alone are `ghosts`: theirs with
/// [`GHOST_HEADROOM_EV`], or `None` when no ghost pixel is lit.
pub fn ghost_exposure(ghosts: &HdrImage) -> Option<f32> {
    lit_exposure(ghosts).map(|ev| ev + GHOST_HEADROOM_EV)
}

/// [`auto_exposure`], or `None` when no pixel is lit.
pub fn lit_exposure(img: &HdrImage) -> Option<f32> {
    let mut lum: Vec<f32> = img
        .pixels
        .iter()
        .map(|p| 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2])
        .filter(|&l| l > 0.0)
        .collect();
    if lum.is_empty() {
        return None;
    }
    let k = ((lum.len() as f64 * 0.999) as usize).min(lum.len() - 1);
    let (_, &mut p, _) = lum.select_nth_unstable_by(k, f32::total_cmp);
    Some(-p.log2())
}
