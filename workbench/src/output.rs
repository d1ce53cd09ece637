//! Writing rendered images: OpenEXR (linear, 32-bit or 16-bit float, lossless ZIP) and PNG (tone mapped,
//! sRGB-encoded, 8 bits per channel), chosen by the file's extension, saved atomically (a
//! temporary file beside the target, synced, then renamed over it).
//!
//! **Tone mapping for PNG** ([`ToneMap`]): each linear channel is multiplied by the exposure
//! `2^EV`, mapped to [0, 1] by the operator — the ACES filmic fit of Narkowicz (2015),
//! `f(x) = x (2.51 x + 0.03) / (x (2.43 x + 0.59) + 0.14)` per channel, which rolls bright
//! ghosts off to white instead of clipping them, or a plain clamp — then encoded with the sRGB
//! transfer function (IEC 61966-2-1) and rounded to 8 bits. Negative and NaN values become 0.
//! EXR files keep the linear values exactly in f32; half floats ([`ExrPrecision::Half`]) round
//! each value to the nearest f16 (11 significant bits, largest finite 65504; larger values
//! become +∞).

use std::io::Cursor;
use std::path::Path;

use anyhow::{Context, Result, bail, ensure};
use flarebench_sdk::color::srgb;
use flarebench_sdk::image::HdrImage;
use flarebench_sdk::io::write_atomically;

/// An output file format.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum OutputFormat {
    /// OpenEXR, linear f32 RGB, ZIP compression (lossless).
    Exr,
    /// PNG, tone mapped 8-bit sRGB.
    Png,
}

impl OutputFormat {
    /// The format named by `path`'s extension (`.exr` or `.png`, any case).
    pub fn from_path(path: &Path) -> Result<OutputFormat> {
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase);
        match ext.as_deref() {
            Some("exr") => Ok(OutputFormat::Exr),
            Some("png") => Ok(OutputFormat::Png),
            _ => bail!(
                "`{}`: unknown image extension; use .exr (linear HDR) or .png (tone mapped)",
                path.display()
            ),
        }
    }
}

/// The curve that maps exposed linear values to [0, 1] for PNG.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, clap::ValueEnum)]
pub enum ToneOperator {
    /// Narkowicz's ACES filmic fit, per channel (highlights roll off to white).
    #[default]
    Aces,
    /// Clamp to [0, 1] (linear; exact values below 1).
    Clamp,
}

/// How a linear HDR image becomes an 8-bit PNG.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ToneMap {
    /// Exposure in stops: linear values are multiplied by `2^exposure_ev` first.
    pub exposure_ev: f32,
    /// The tone curve.
    pub operator: ToneOperator,
}

impl Default for ToneMap {
    fn default() -> Self {
        ToneMap {
            exposure_ev: 0.0,
            operator: ToneOperator::Aces,
        }
    }
}

impl ToneMap {
    /// One channel: exposure, tone curve, sRGB encoding, 8 bits.
    pub fn map_channel(&self, linear: f32) -> u8 {
        let x = linear * self.exposure_ev.exp2();
        // NaN and negatives become 0 here (`max` returns the non-NaN operand).
        let x = x.max(0.0);
        let y = match self.operator {
            ToneOperator::Aces => (x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14),
            ToneOperator::Clamp => x,
        };
        // `encode` clamps to [0, 1]. Past about 1.8e19 the ACES ratio's x² overflows (∞/∞ is
        // NaN, which would encode as black); from 1e9 up the ratio is above 1 (it tends to
        // 2.51/2.43) and would clamp to white anyway.
        let y = if x > 1e9 { 1.0 } else { y };
        (srgb::encode(y) * 255.0).round() as u8
    }
}

/// A [`ToneMap`] as the 255 thresholds between its 8-bit levels: level `k` starts at the
/// smallest linear value that `map_channel` takes to `k` or above, so a value's level is the
/// number of thresholds at or below it — eight comparisons instead of an `exp2`, the tone curve
/// and a `powf`. `map_channel`'s f32 arithmetic is not quite monotone (the ACES ratio rounds
/// up and down as its value grows), so near a threshold a value may land one level from
/// `map_channel`'s; elsewhere the two agree (tested). The viewer tones its preview with it;
/// the PNG writer keeps `map_channel`. Building it costs about 8 000 `map_channel` calls.
#[derive(Clone, Debug)]
pub struct ToneTable {
    thresholds: [f32; 255],
}

impl ToneTable {
    /// The thresholds of `tone`, found by bisection over the non-negative f32 values (whose
    /// bit patterns sort as the values do).
    pub fn new(tone: &ToneMap) -> ToneTable {
        // A level no value reaches keeps NaN, which no value is at or above.
        let mut thresholds = [f32::NAN; 255];
        for (i, t) in thresholds.iter_mut().enumerate() {
            let level = i as u8 + 1;
            // The first bit pattern in [0, +∞] whose level is at least `level`.
            let (mut lo, mut hi) = (0u32, f32::INFINITY.to_bits());
            if tone.map_channel(f32::from_bits(hi)) < level {
                continue;
            }
            while lo < hi {
                let mid = lo + (hi - lo) / 2;
                if tone.map_channel(f32::from_bits(mid)) >= level {
                    hi = mid;
                } else {
                    lo = mid + 1;
                }
            }
            *t = f32::from_bits(lo);
        }
        ToneTable { thresholds }
    }

    /// The 8-bit level of `linear` (NaN and negatives: 0), as `ToneMap::map_channel`.
    #[inline]
    pub fn map(&self, linear: f32) -> u8 {
        // NaN compares false with every threshold, and a negative or zero value is below the
        // first (positive) one: both count none.
        self.thresholds.partition_point(|&t| t <= linear) as u8
    }
}

/// The sample type of an EXR file.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum ExrPrecision {
    /// 32-bit float (exact).
    #[default]
    Float,
    /// 16-bit half float (half the size; see the module docs).
    Half,
}

/// Saves `img` to `path` as EXR (f32) or PNG (by extension), atomically.
/// A file-name stem made from `text`: ASCII letters and digits in lower case, every run of
/// other characters one `-`, none at either end (empty when `text` has no letter or digit).
pub fn file_stem(text: &str) -> String {
    let mut s = String::with_capacity(text.len());
    for c in text.chars() {
        if c.is_ascii_alphanumeric() {
            s.push(c.to_ascii_lowercase());
        } else if !s.is_empty() && !s.ends_with('-') {
            s.push('-');
        }
    }
    s.trim_end_matches('-').to_string()
}

pub fn save_image(img: &HdrImage, path: &Path, tone: &ToneMap) -> Result<()> {
    save_image_as(img, path, tone, ExrPrecision::Float)
}

/// [`save_image`] with the EXR sample type chosen.
pub fn save_image_as(
    img: &HdrImage,
    path: &Path,
    tone: &ToneMap,
    precision: ExrPrecision,
) -> Result<()> {
    let bytes = match OutputFormat::from_path(path)? {
        OutputFormat::Exr if precision == ExrPrecision::Half => encode_exr_half(img),
        OutputFormat::Exr => encode_exr(img),
        OutputFormat::Png => encode_png(img, tone),
    }
    .with_context(|| format!("could not encode `{}`", path.display()))?;
    write_atomically(path, &bytes).with_context(|| format!("could not write `{}`", path.display()))
}

/// The image as an OpenEXR file in memory: one layer, channels R, G, B as f32, ZIP
/// compression in blocks of 16 scan lines (lossless).
pub fn encode_exr(img: &HdrImage) -> Result<Vec<u8>> {
    encode_exr_with(img, &[])
}

/// [`encode_exr`] with text attributes `(name, value)` on the layer (as
/// [`read_exr_with_attributes`] gives them back).
pub fn encode_exr_with(img: &HdrImage, text: &[(&str, &str)]) -> Result<Vec<u8>> {
    use exr::prelude::*;
    check_size(img)?;
    let width = img.width;
    let pixels = &img.pixels;
    let mut attributes = LayerAttributes::named("flarebench");
    for &(name, value) in text {
        attributes.other.insert(
            Text::new_or_none(name).context("attribute name is not EXR text")?,
            AttributeValue::Text(
                Text::new_or_none(value).context("attribute value is not EXR text")?,
            ),
        );
    }
    let layer = Layer::new(
        (img.width, img.height),
        attributes,
        Encoding::SMALL_LOSSLESS,
        SpecificChannels::rgb(|pos: Vec2<usize>| {
            let p = pixels[pos.y() * width + pos.x()];
            (p[0], p[1], p[2])
        }),
    );
    let mut bytes = Cursor::new(Vec::new());
    Image::from_layer(layer)
        .write()
        .to_buffered(&mut bytes)
        .map_err(|e| anyhow::anyhow!("EXR encoder: {e}"))?;
    Ok(bytes.into_inner())
}

/// The image as a half-float OpenEXR file in memory (channels R, G, B as f16, ZIP).
pub fn encode_exr_half(img: &HdrImage) -> Result<Vec<u8>> {
    use exr::prelude::*;
    check_size(img)?;
    let width = img.width;
    let pixels = &img.pixels;
    let layer = Layer::new(
        (img.width, img.height),
        LayerAttributes::named("flarebench"),
        Encoding::SMALL_LOSSLESS,
        SpecificChannels::rgb(|pos: Vec2<usize>| {
            let p = pixels[pos.y() * width + pos.x()];
            (
                f16::from_f32(p[0]),
                f16::from_f32(p[1]),
                f16::from_f32(p[2]),
            )
        }),
    );
    let mut bytes = Cursor::new(Vec::new());
    Image::from_layer(layer)
        .write()
        .to_buffered(&mut bytes)
        .map_err(|e| anyhow::anyhow!("EXR encoder: {e}"))?;
    Ok(bytes.into_inner())
}

/// Saves 8-bit sRGB pixels already tone mapped (RGB, row-major: the GPU backend's tone pass)
/// as a PNG, atomically.
pub fn save_png_rgb8(rgb: Vec<u8>, width: usize, height: usize, path: &Path) -> Result<()> {
    let img = image::RgbImage::from_raw(width as u32, height as u32, rgb)
        .context("pixel buffer does not match the image size")?;
    let mut bytes = Cursor::new(Vec::new());
    img.write_to(&mut bytes, image::ImageFormat::Png)
        .context("PNG encoder")?;
    write_atomically(path, bytes.get_ref())
        .with_context(|| format!("could not write `{}`", path.display()))
}

/// The image tone mapped to an 8-bit sRGB PNG in memory.
pub fn encode_png(img: &HdrImage, tone: &ToneMap) -> Result<Vec<u8>> {
    check_size(img)?;
    let raw: Vec<u8> = img
        .pixels
        .iter()
        .flat_map(|p| p.map(|c| tone.map_channel(c)))
        .collect();
    let rgb = image::RgbImage::from_raw(img.width as u32, img.height as u32, raw)
        .context("pixel buffer does not match the image size")?;
    let mut bytes = Cursor::new(Vec::new());
    rgb.write_to(&mut bytes, image::ImageFormat::Png)
        .context("PNG encoder")?;
    Ok(bytes.into_inner())
}

/// Reads the first RGB(A) layer of an OpenEXR file as a linear image (alpha ignored; f16 and
/// u32 channels are converted to f32).
pub fn read_exr(path: &Path) -> Result<HdrImage> {
    Ok(read_exr_with_attributes(path)?.0)
}

/// [`read_exr`] and the first layer's text attributes (name → value).
pub fn read_exr_with_attributes(
    path: &Path,
) -> Result<(HdrImage, std::collections::BTreeMap<String, String>)> {
    let image = exr::prelude::read_first_rgba_layer_from_file(
        path,
        |size, _| HdrImage::new(size.width(), size.height()),
        |img: &mut HdrImage, pos, (r, g, b, _a): (f32, f32, f32, f32)| {
            let w = img.width;
            img.pixels[pos.y() * w + pos.x()] = [r, g, b];
        },
    )
    .map_err(|e| anyhow::anyhow!("{e}"))
    .with_context(|| format!("could not read OpenEXR image `{}`", path.display()))?;
    let text = image
        .layer_data
        .attributes
        .other
        .iter()
        .filter_map(|(k, v)| match v {
            exr::meta::attribute::AttributeValue::Text(t) => Some((k.to_string(), t.to_string())),
            _ => None,
        })
        .collect();
    Ok((image.layer_data.channel_data.pixels, text))
}

fn check_size(img: &HdrImage) -> Result<()> {
    ensure!(
        img.width > 0 && img.height > 0,
        "cannot write an empty {}×{} image",
        img.width,
        img.height
    );
    ensure!(
        u32::try_from(img.width).is_ok() && u32::try_from(img.height).is_ok(),
        "image {}×{} is too large to save",
        img.width,
        img.height
    );
    ensure!(
        img.pixels.len() == img.width * img.height,
        "image has {} pixels for {}×{}",
        img.pixels.len(),
        img.width,
        img.height
    );
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::fs;

    #[test]
    fn file_stems_keep_letters_and_digits_and_one_dash_between() {
        assert_eq!(file_stem("Heliar-Tronnier"), "heliar-tronnier");
        assert_eq!(file_stem("  Nikon 28–70 mm / f2.8 "), "nikon-28-70-mm-f2-8");
        assert_eq!(
            file_stem("heliar-tronnier-10.5-30"),
            "heliar-tronnier-10-5-30"
        );
        assert_eq!(file_stem("°°"), "");
    }

    /// A fresh directory, removed when the returned `TempDir` is dropped.
    fn temp_dir(tag: &str) -> tempfile::TempDir {
        tempfile::Builder::new()
            .prefix(&format!("flarebench-output-{tag}-"))
            .tempdir()
            .unwrap()
    }

    /// Values that stress f32: tiny, huge, negative, subnormal, non-round.
    fn test_image() -> HdrImage {
        let (w, h) = (37, 23);
        let pixels = (0..w * h)
            .map(|i| {
                let t = i as f32;
                [
                    t * 0.123_456_7 + 1e-7,
                    (t * 0.37).sin() * 1e4,
                    if i % 7 == 0 {
                        -2.5e-3
                    } else {
                        f32::MIN_POSITIVE / 3.0 * t
                    },
                ]
            })
            .collect();
        HdrImage::from_pixels(w, h, pixels).unwrap()
    }

    #[test]
    fn exr_round_trips_f32_exactly() {
        let tmp = temp_dir("exr");
        let dir = tmp.path();
        let path = dir.join("flare.exr");
        let img = test_image();
        save_image(&img, &path, &ToneMap::default()).unwrap();
        let back = read_exr(&path).unwrap();
        assert_eq!((back.width, back.height), (img.width, img.height));
        for (a, b) in img.pixels.iter().zip(&back.pixels) {
            assert_eq!(a.map(f32::to_bits), b.map(f32::to_bits));
        }
        // Saving again replaces the file and leaves no temporary behind.
        save_image(&img, &path, &ToneMap::default()).unwrap();
        let names: Vec<_> = fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .collect();
        assert_eq!(names, vec![std::ffi::OsString::from("flare.exr")]);
        tmp.close().unwrap();
    }

    #[test]
    fn half_exr_rounds_to_f16_and_is_smaller() {
        let tmp = temp_dir("exr-half");
        let dir = tmp.path();
        let (full, half) = (dir.join("f.exr"), dir.join("h.exr"));
        let img = HdrImage::from_pixels(
            4,
            1,
            vec![
                [0.1, 1.0, 3.0],
                [1e5, 0.0, 2049.0],
                [6.0e-8, 0.333, 0.5],
                [1.0; 3],
            ],
        )
        .unwrap();
        save_image_as(&img, &half, &ToneMap::default(), ExrPrecision::Half).unwrap();
        save_image(&img, &full, &ToneMap::default()).unwrap();
        let back = read_exr(&half).unwrap();
        // f16: 0.1 → 0.099975586, 0.333 → 0.33300781, 2049 → 2048 (ties to even), 1e5 → +∞
        // (beyond 65504), 6e-8 → the subnormal 5.96e-8.
        assert_eq!(back.pixels[0], [0.099_975_586, 1.0, 3.0]);
        assert_eq!(back.pixels[1], [f32::INFINITY, 0.0, 2048.0]);
        assert_eq!(back.pixels[2], [5.960_464_5e-8, 0.333_007_8, 0.5]);
        assert!(fs::metadata(&half).unwrap().len() < fs::metadata(&full).unwrap().len());
        tmp.close().unwrap();
    }

    #[test]
    fn png_is_tone_mapped_srgb() {
        let tmp = temp_dir("png");
        let dir = tmp.path();
        let path = dir.join("flare.PNG");
        let pixels = vec![
            [0.0, 0.18, 1.0],
            [1e9, -1.0, f32::NAN],
            [0.5, 0.002, f32::INFINITY],
        ];
        let img = HdrImage::from_pixels(3, 1, pixels).unwrap();
        let clamp = ToneMap {
            exposure_ev: 0.0,
            operator: ToneOperator::Clamp,
        };
        save_image(&img, &path, &clamp).unwrap();
        let back = image::open(&path).unwrap().to_rgb8();
        assert_eq!((back.width(), back.height()), (3, 1));
        // Clamp + sRGB: 0.18 → 0.4614 → 118; 0.5 → 0.7354 → 188; 0.002 → 0.02584 → 7.
        assert_eq!(back.get_pixel(0, 0).0, [0, 118, 255]);
        assert_eq!(back.get_pixel(1, 0).0, [255, 0, 0]);
        assert_eq!(back.get_pixel(2, 0).0, [188, 7, 255]);
        tmp.close().unwrap();
    }

    #[test]
    fn aces_rolls_off_and_exposure_scales() {
        let aces = ToneMap::default();
        // f(0.18) = 0.18 (2.51·0.18 + 0.03) / (0.18 (2.43·0.18 + 0.59) + 0.14) = 0.2669
        // → sRGB 0.5535 → 141.1 → 141.
        assert_eq!(aces.map_channel(0.18), 141);
        // The fit saturates: f(∞) = 2.51 / 2.43 > 1, clamped to 255 from about x = 10.
        assert_eq!(aces.map_channel(100.0), 255);
        assert!(aces.map_channel(1.0) < 255 && aces.map_channel(1.0) > 200);
        assert_eq!(aces.map_channel(f32::INFINITY), 255);
        assert_eq!(aces.map_channel(1e25), 255, "x² overflows: still white");
        assert_eq!(aces.map_channel(f32::NAN), 0);
        assert_eq!(aces.map_channel(-3.0), 0);
        let plus_one = ToneMap {
            exposure_ev: 1.0,
            operator: ToneOperator::Clamp,
        };
        let clamp = ToneMap {
            exposure_ev: 0.0,
            operator: ToneOperator::Clamp,
        };
        assert_eq!(plus_one.map_channel(0.09), clamp.map_channel(0.18));
    }

    /// The tone table gives `map_channel`'s level within one, and the same level for all but a
    /// few values next to a threshold (a thousand f32 steps either side of each), at several
    /// exposures and both operators; the same level for random values, zero, negatives, NaN
    /// and infinity.
    #[test]
    fn the_tone_table_equals_the_tone_map() {
        for operator in [ToneOperator::Aces, ToneOperator::Clamp] {
            for exposure_ev in [-20.0, -3.5, 0.0, 1.0, 12.25] {
                let tone = ToneMap {
                    exposure_ev,
                    operator,
                };
                let table = ToneTable::new(&tone);
                let (mut near, mut off) = (0usize, 0usize);
                for &t in &table.thresholds {
                    if !t.is_finite() {
                        continue;
                    }
                    let b = t.to_bits() as i64;
                    for d in -1000..=1000i64 {
                        let x = f32::from_bits((b + d).clamp(0, 0x7f80_0000) as u32);
                        let (a, e) = (table.map(x), tone.map_channel(x));
                        assert!(a.abs_diff(e) <= 1, "{tone:?} at {x:e}: {a} against {e}");
                        near += 1;
                        off += usize::from(a != e);
                    }
                }
                assert!(
                    off * 200 <= near,
                    "{tone:?}: {off} of {near} values off by one"
                );
                let mut state = 0x9e37_79b9_7f4a_7c15u64;
                for _ in 0..100_000 {
                    state ^= state << 13;
                    state ^= state >> 7;
                    state ^= state << 17;
                    // Values from 1e-12 to 1e6, log-uniform.
                    let x = 10f32.powf(-12.0 + 18.0 * (state >> 40) as f32 / (1u64 << 24) as f32);
                    assert_eq!(table.map(x), tone.map_channel(x), "{tone:?} at {x:e}");
                }
                for x in [0.0, -0.0, -1.0, f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
                    assert_eq!(table.map(x), tone.map_channel(x), "{tone:?} at {x}");
                }
            }
        }
    }

    #[test]
    fn the_extension_picks_the_format_and_bad_ones_are_errors() {
        assert_eq!(
            OutputFormat::from_path(Path::new("a/b.EXR")).unwrap(),
            OutputFormat::Exr
        );
        assert_eq!(
            OutputFormat::from_path(Path::new("b.png")).unwrap(),
            OutputFormat::Png
        );
        let err = save_image(&test_image(), Path::new("out.jpg"), &ToneMap::default());
        assert!(format!("{:#}", err.unwrap_err()).contains("unknown image extension"));
        let empty = HdrImage::new(0, 3);
        assert!(encode_exr(&empty).is_err());
        assert!(encode_png(&empty, &ToneMap::default()).is_err());
        let missing = Path::new("/nonexistent-flarebench-dir/x.exr");
        assert!(save_image(&test_image(), missing, &ToneMap::default()).is_err());
        assert!(read_exr(missing).is_err());
    }
}
