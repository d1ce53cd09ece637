//! A sample's annotation (`samples/NNNNNNNN.json`): every sampled parameter (the
//! [`SampleSpec`]), the lens's working figures, each light's direction and pixel position,
//! each drawn ghost's id, energy and bounding box, and the render's figures. Nothing in it
//! depends on the machine or the time, so it is the same bytes wherever it is made.
//!
//! **Ghost boxes** ([`GhostMeasure::of`]): a ghost's energy is the luminance (Rec. 709
//! weights) summed over its image on the frame. Its box trims [`BOX_TAIL`] of that energy
//! from each of its four sides by the image's column and row sums, so it holds at least
//! `1 − 4·BOX_TAIL` = 99% of it (the share it holds exactly is given too).

use flarebench_sdk::color::srgb::luminance_f32;
use flarebench_sdk::image::HdrImage;
use serde::Serialize;

use super::sampler::SampleSpec;

/// The share of a ghost's energy a box may leave out on each of its four sides: 0.25%, so
/// the box holds at least 99% of the ghost's energy on the frame.
pub const BOX_TAIL: f64 = 0.0025;

/// What a sample is and holds.
#[derive(Clone, Debug, Serialize)]
pub struct Annotation {
    /// The format of this file.
    pub format: &'static str,
    /// Every sampled parameter.
    pub sample: SampleSpec,
    pub lens: LensFigures,
    pub lights: Vec<LightAnnotation>,
    /// Every ghost drawn, light by light in plan order; `id` is its value in the ID layer.
    pub ghosts: Vec<GhostAnnotation>,
    pub figures: RenderFigures,
    /// The image files' channels (`R`, `G`, `B` the flare; `ghosts.R`, …).
    pub channels: Vec<String>,
}

/// The lens as rendered.
#[derive(Clone, Debug, Serialize)]
pub struct LensFigures {
    /// The lens's own name.
    pub title: String,
    /// Paraxial focal length (mm, primary wavelength).
    pub efl_mm: f64,
    /// The f-number it was rendered at: the one drawn, or wide open when it opens less far.
    pub working_f_number: f64,
    pub open_f_number: f64,
    /// The film's width and the frame's height on it (mm).
    pub film_width_mm: f64,
    pub film_height_mm: f64,
}

/// One light as rendered.
#[derive(Clone, Debug, Serialize)]
pub struct LightAnnotation {
    pub light: usize,
    pub theta_deg: f64,
    pub phi_deg: f64,
    /// Where its chief ray lands (pixels, x right, y down), if it reaches the sensor.
    pub position_px: Option<[f64; 2]>,
    pub inside_frame: bool,
    /// Its colour: the blackbody's linear sRGB, luminance 1.
    pub rgb: [f64; 3],
    /// Its ghosts drawn and left out by the plan, and the share of its ghost energy on the
    /// frame the plan left out as too dim.
    pub ghosts_drawn: usize,
    pub ghosts_left_out: usize,
    pub culled_share: f64,
    /// Its starburst's flux through the lens, and the luminance it adds to the frame (0
    /// without starbursts).
    pub starburst_flux: f64,
    pub starburst_added: f64,
}

/// One drawn ghost.
#[derive(Clone, Debug, Serialize)]
pub struct GhostAnnotation {
    /// 1, 2, …: its value in the `ghost_id` layer (0 there is no ghost).
    pub id: u32,
    pub light: usize,
    /// The surfaces it reflects at (`a-b`, as `render --report` names ghosts).
    pub path: String,
    #[serde(flatten)]
    pub measure: GhostMeasure,
    /// Flux of its rasterised triangles before the frame crops it.
    pub flux: f64,
}

/// A ghost's energy on the frame and where it lies.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct GhostMeasure {
    /// Luminance summed over its pixels.
    pub energy: f64,
    /// `[x0, y0, x1, y1]` (pixels, x1 and y1 excluded) holding at least 99% of `energy`;
    /// null when the ghost leaves no light on the frame.
    pub box_px: Option<[usize; 4]>,
    /// The share of `energy` inside `box_px`.
    pub box_share: f64,
    /// Every pixel it lights lies in `[x0, y0, x1, y1]`.
    pub extent_px: Option<[usize; 4]>,
}

impl GhostMeasure {
    /// The measure of a ghost's image (its light alone, on a black frame).
    pub fn of(img: &HdrImage) -> GhostMeasure {
        let (w, h) = (img.width, img.height);
        let mut cols = vec![0f64; w];
        let mut rows = vec![0f64; h];
        for (y, row) in img.pixels.chunks_exact(w.max(1)).enumerate() {
            for (x, p) in row.iter().enumerate() {
                let l = f64::from(luminance_f32(*p)).max(0.0);
                cols[x] += l;
                rows[y] += l;
            }
        }
        let energy: f64 = rows.iter().sum();
        #[allow(
            clippy::neg_cmp_op_on_partial_ord,
            reason = "NaN-aware: a NaN energy is no energy"
        )]
        if !(energy > 0.0) {
            return GhostMeasure {
                energy: 0.0,
                box_px: None,
                box_share: 0.0,
                extent_px: None,
            };
        }
        let tail = BOX_TAIL * energy;
        let (x0, x1) = trimmed(&cols, tail);
        let (y0, y1) = trimmed(&rows, tail);
        let (e0, e1) = trimmed(&cols, 0.0);
        let (f0, f1) = trimmed(&rows, 0.0);
        let mut inside = 0f64;
        for y in y0..y1 {
            for p in &img.pixels[y * w + x0..y * w + x1] {
                inside += f64::from(luminance_f32(*p)).max(0.0);
            }
        }
        GhostMeasure {
            energy,
            box_px: Some([x0, y0, x1, y1]),
            box_share: inside / energy,
            extent_px: Some([e0, f0, e1, f1]),
        }
    }
}

impl GhostMeasure {
    /// This measure of a window moved to where the window lies in the frame (its top-left
    /// pixel at `(x0, y0)`). A ghost's window holds every pixel it lights, so this is the
    /// measure of its whole frame, bit for bit: the pixels outside add zeros.
    pub fn at(self, x0: usize, y0: usize) -> GhostMeasure {
        let shift = |b: [usize; 4]| [b[0] + x0, b[1] + y0, b[2] + x0, b[3] + y0];
        GhostMeasure {
            box_px: self.box_px.map(shift),
            extent_px: self.extent_px.map(shift),
            ..self
        }
    }
}

/// The span `lo..hi` of `sums` left when no more than `tail` is cut from each end (every
/// non-zero entry with `tail` 0).
fn trimmed(sums: &[f64], tail: f64) -> (usize, usize) {
    let mut acc = 0.0;
    let mut lo = 0;
    for (i, s) in sums.iter().enumerate() {
        acc += s;
        if acc > tail {
            lo = i;
            break;
        }
    }
    acc = 0.0;
    let mut hi = sums.len();
    for (i, s) in sums.iter().enumerate().rev() {
        acc += s;
        if acc > tail {
            hi = i + 1;
            break;
        }
    }
    (lo, hi.max(lo + 1))
}

/// The render's figures.
#[derive(Clone, Debug, Serialize)]
pub struct RenderFigures {
    pub ghosts_drawn: usize,
    pub ghosts_left_out: usize,
    pub rays_traced: usize,
    pub triangles: usize,
    /// Sums of the linear layers, per channel.
    pub flare_sum_rgb: [f64; 3],
    pub ghosts_sum_rgb: [f64; 3],
    pub starburst_sum_rgb: Option<[f64; 3]>,
    pub flare_max: f32,
    /// The automatic exposure (stops): the PNG's unless the sampler fixes it.
    pub exposure_ev: f32,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_box_trims_a_quarter_percent_from_each_side() {
        // A 10×1 row: a bright pixel at 5 (1000) and faint ones at 0 and 9 (1 each, 0.1% of
        // the energy each): the box is the bright pixel alone, the extent the whole row.
        let mut img = HdrImage::new(10, 1);
        img.pixels[0] = [1.0; 3];
        img.pixels[5] = [1000.0; 3];
        img.pixels[9] = [1.0; 3];
        let m = GhostMeasure::of(&img);
        assert_eq!(m.box_px, Some([5, 0, 6, 1]));
        assert_eq!(m.extent_px, Some([0, 0, 10, 1]));
        assert!((m.box_share - 1000.0 / 1002.0).abs() < 1e-6);
        assert!(m.box_share >= 1.0 - 4.0 * BOX_TAIL);
        assert_eq!(GhostMeasure::of(&HdrImage::new(4, 4)).box_px, None);
    }
}
