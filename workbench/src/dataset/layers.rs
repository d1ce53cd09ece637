//! A sample's files in memory: the layers as one OpenEXR image with named channels — `R`,
//! `G`, `B` the flare; `ghosts.R`, `ghosts.G`, `ghosts.B`; `starburst.*`; `light0.*`, … (f32);
//! `ghost_id` (u32) — ZIP compressed, written without parallel compression so the bytes do
//! not depend on the thread count; the tone-mapped PNG; and [`read_channels`] to read such a
//! file back by channel name.

use std::collections::BTreeMap;
use std::io::Cursor;
use std::path::Path;

use anyhow::Context;
use flarebench_sdk::image::HdrImage;

use super::sample::SampleOutput;
use crate::output::{ToneMap, ToneOperator, encode_png};

/// The channel name of channel `c` (0 R, 1 G, 2 B) of layer `layer` (empty: the flare).
fn channel(layer: &str, c: usize) -> String {
    let rgb = ["R", "G", "B"][c];
    if layer.is_empty() {
        rgb.to_string()
    } else {
        format!("{layer}.{rgb}")
    }
}

/// The names of `out`'s channels, sorted as the EXR file stores them.
pub fn channel_names(out: &SampleOutput) -> Vec<String> {
    let mut names: Vec<String> = out
        .float_layers()
        .iter()
        .flat_map(|(l, _)| (0..3).map(|c| channel(l, c)))
        .collect();
    if out.ghost_id.is_some() {
        names.push("ghost_id".into());
    }
    names.sort();
    names
}

/// The sample's layers as an OpenEXR file in memory.
pub fn encode_exr(out: &SampleOutput) -> anyhow::Result<Vec<u8>> {
    use exr::prelude::*;
    let (w, h) = (out.flare.width, out.flare.height);
    let mut list: SmallVec<[AnyChannel<FlatSamples>; 4]> = SmallVec::new();
    for (layer, img) in out.float_layers() {
        for c in 0..3 {
            let samples: Vec<f32> = img.pixels.iter().map(|p| p[c]).collect();
            list.push(AnyChannel::new(
                channel(&layer, c).as_str(),
                FlatSamples::F32(samples),
            ));
        }
    }
    if let Some(ids) = &out.ghost_id {
        list.push(AnyChannel::new("ghost_id", FlatSamples::U32(ids.clone())));
    }
    let layer = Layer::new(
        (w, h),
        LayerAttributes::named("flarebench"),
        Encoding::SMALL_LOSSLESS,
        AnyChannels::sort(list),
    );
    let mut bytes = Cursor::new(Vec::new());
    Image::from_layer(layer)
        .write()
        .non_parallel()
        .to_buffered(&mut bytes)
        .map_err(|e| anyhow::anyhow!("EXR encoder: {e}"))?;
    Ok(bytes.into_inner())
}

/// The flare tone mapped (ACES) at `exposure_ev` as a PNG in memory.
pub fn encode_preview(out: &SampleOutput, exposure_ev: f32) -> anyhow::Result<Vec<u8>> {
    encode_png(
        &out.flare,
        &ToneMap {
            exposure_ev,
            operator: ToneOperator::Aces,
        },
    )
}

/// Channels by name: each one's samples, row-major.
pub type Channels = BTreeMap<String, Vec<f64>>;

/// The channels of a file [`encode_exr`] wrote, by name: the image size and each channel's
/// samples (row-major; `ghost_id` as exact whole numbers in f64, the rest widened from f32).
pub fn read_channels(path: &Path) -> anyhow::Result<((usize, usize), Channels)> {
    use exr::prelude::*;
    let image = read_first_flat_layer_from_file(path)
        .map_err(|e| anyhow::anyhow!("{e}"))
        .with_context(|| format!("could not read OpenEXR image `{}`", path.display()))?;
    let size = image.layer_data.size;
    let mut out = BTreeMap::new();
    for ch in &image.layer_data.channel_data.list {
        let values: Vec<f64> = match &ch.sample_data {
            FlatSamples::F32(v) => v.iter().map(|&x| f64::from(x)).collect(),
            FlatSamples::F16(v) => v.iter().map(|&x| f64::from(x.to_f32())).collect(),
            FlatSamples::U32(v) => v.iter().map(|&x| f64::from(x)).collect(),
        };
        out.insert(ch.name.to_string(), values);
    }
    Ok(((size.width(), size.height()), out))
}

/// The RGB layer `layer` (empty: the flare) of channels read by [`read_channels`].
pub fn layer_image((w, h): (usize, usize), channels: &Channels, layer: &str) -> Option<HdrImage> {
    let r = channels.get(&channel(layer, 0))?;
    let g = channels.get(&channel(layer, 1))?;
    let b = channels.get(&channel(layer, 2))?;
    let pixels = (0..w * h)
        .map(|i| [r[i] as f32, g[i] as f32, b[i] as f32])
        .collect();
    HdrImage::from_pixels(w, h, pixels).ok()
}
