//! The GPU image of a frame equals the CPU image of the same frame description
//! (`flarebench_sdk::ghost::sink::FrameMeshes`, drawn by both): relative RMSE and energy
//! within the bounds, and no NaN or Inf.

use std::sync::{Arc, OnceLock};

use flarebench_gpu::{AccumFormat, AdapterChoice, GhostRenderer, GpuContext};
use flarebench_sdk::aperture::Aperture;
use flarebench_sdk::frame::Frame;
use flarebench_sdk::ghost::fringe::APERTURE_FLAG;
use flarebench_sdk::ghost::sink::FrameMeshes;
use flarebench_sdk::image::HdrImage;
use flarebench_sdk::starburst::StarburstSplat;
use flarebench_test_support::load_lens;
use ghost_raytrace::ghosts::{self, RenderOptions};
use ghost_raytrace::plan::{self, DrawMethod, PlanOptions};
use ghost_raytrace::scene::{LightSpec, Quality};

/// Relative RMSE of the GPU image against the CPU image.
const MAX_RMSE: f64 = 0.005;
/// Relative difference of the images' luminance sums.
const MAX_ENERGY: f64 = 0.001;

fn context() -> Arc<GpuContext> {
    static CTX: OnceLock<Arc<GpuContext>> = OnceLock::new();
    CTX.get_or_init(|| Arc::new(GpuContext::new(AdapterChoice::Any).expect("a GPU adapter")))
        .clone()
}

fn record(lens: &str, lights: &[&str], aperture: &Aperture, band_by_band: bool) -> FrameMeshes {
    let sys = load_lens(lens);
    let frame = Frame::across_film(960, 540, sys.film_width_mm);
    let lights: Vec<LightSpec> = lights
        .iter()
        .map(|l| LightSpec::parse(l).unwrap())
        .collect();
    let opts = PlanOptions::for_quality(Quality::Default, None);
    let plans = plan::plan(&sys, &lights, &frame, &opts).unwrap();
    let options = RenderOptions {
        band_by_band,
        ..RenderOptions::default()
    };
    let mut recorded = FrameMeshes::default();
    ghosts::draw_into(&sys, aperture, frame, &plans, options, &mut recorded).unwrap();
    recorded
}

/// The GPU image of `recorded`, accumulated in `accum` times 2^`scale_log2`, with `splats`
/// added after the ghosts.
fn gpu_image(
    recorded: &FrameMeshes,
    splats: &[StarburstSplat],
    accum: AccumFormat,
    scale_log2: i32,
) -> HdrImage {
    let mut gpu = GhostRenderer::new(context(), accum).expect("a renderer");
    gpu.set_scale_log2(scale_log2);
    recorded.replay(&mut gpu);
    if !splats.is_empty() {
        gpu.add_starbursts(splats).expect("the starbursts");
    }
    gpu.read_back().expect("the GPU frame")
}

fn check(name: &str, recorded: &FrameMeshes) {
    let cpu = recorded.draw_cpu();
    let gpu = gpu_image(recorded, &[], AccumFormat::F32, 0);
    assert!(!gpu.has_non_finite(), "{name}: NaN or Inf in the GPU image");
    let c = gpu.compare(&cpu).unwrap();
    eprintln!(
        "{name}: {} triangles, levels {:?}: rmse {:.2e}, energy {:.2e}",
        recorded.triangles(),
        recorded
            .levels
            .as_ref()
            .map(|l| l.1.iter().map(|g| g.factor).collect::<Vec<_>>()),
        c.relative_rmse,
        c.energy_error
    );
    assert!(cpu.luminance_sum() > 0.0, "{name}: the frame is black");
    assert!(
        c.relative_rmse <= MAX_RMSE,
        "{name}: rmse {}",
        c.relative_rmse
    );
    assert!(
        c.energy_error.abs() <= MAX_ENERGY,
        "{name}: energy {}",
        c.energy_error
    );
}

#[test]
fn heliar_circle_fringed_and_band_by_band() {
    let r = record("heliar-tronnier", &["8,60"], &Aperture::Circular, false);
    assert!(
        r.meshes.iter().any(|(_, m)| !m.fringe.is_empty()),
        "the default frame has fringed groups"
    );
    check("heliar circle, fringed", &r);
    let r = record("heliar-tronnier", &["8,60"], &Aperture::Circular, true);
    check("heliar circle, band by band", &r);
}

/// The Nikon zoom's frame with every ghost splatted (`plan::DrawMethod::Splat`): its
/// near-focus ghosts' sub-pixel triangles as box splats, which the GPU draws as pairs of
/// triangles.
#[test]
fn nikon_splatted() {
    let sys = load_lens("nikon-zoom-short");
    let frame = Frame::across_film(480, 270, sys.film_width_mm);
    let lights = [LightSpec::parse("10,30").unwrap()];
    let opts = PlanOptions {
        method: Some(DrawMethod::Splat),
        ..PlanOptions::for_quality(Quality::Default, None)
    };
    let plans = plan::plan(&sys, &lights, &frame, &opts).unwrap();
    let mut recorded = FrameMeshes::default();
    ghosts::draw_into(
        &sys,
        &Aperture::Circular,
        frame,
        &plans,
        RenderOptions::default(),
        &mut recorded,
    )
    .unwrap();
    let boxes: usize = recorded.meshes.iter().map(|(_, m)| m.boxes.len()).sum();
    assert!(boxes > 10_000, "{boxes} boxes");
    check("nikon splatted", &recorded);
}

fn iris() -> Aperture {
    Aperture::Iris {
        blades: 6,
        rotation_rad: 0.3,
        roundness: 0.2,
    }
}

/// OpenLensFlare's own aperture mask (lenses/masks/aperture.bmp).
fn olf_mask() -> Aperture {
    let path = flarebench_test_support::lenses_dir().join("masks/aperture.bmp");
    let img = image::open(&path).expect("the bundled mask").to_luma8();
    let (w, h) = img.dimensions();
    let mask =
        flarebench_sdk::aperture::ApertureMask::from_luma(w as usize, h as usize, img.as_raw())
            .expect("a valid mask");
    Aperture::Mask(mask)
}

/// Fringed groups through an aperture other than the circle: triangles flagged
/// `APERTURE_FLAG`, whose outline the fringe shader steps over τ.
fn has_aperture_fringes(recorded: &FrameMeshes) -> bool {
    recorded
        .meshes
        .iter()
        .any(|(_, m)| m.fringe.attrs.iter().any(|a| a[10] > APERTURE_FLAG - 0.5))
}

#[test]
fn heliar_iris_and_mask() {
    for (name, aperture) in [("iris", iris()), ("mask", olf_mask())] {
        let r = record("heliar-tronnier", &["8,60"], &aperture, false);
        assert!(
            has_aperture_fringes(&r),
            "{name}: the frame has fringed outlines"
        );
        check(&format!("heliar {name}, fringed"), &r);
    }
}

#[test]
#[ignore = "slow tier: two more frames on lavapipe; by default the iris and the mask fringed, \
            and the circle band by band (`heliar_circle_fringed_and_band_by_band`)"]
fn heliar_iris_and_mask_band_by_band() {
    for (name, aperture) in [("iris", iris()), ("mask", olf_mask())] {
        let r = record("heliar-tronnier", &["8,60"], &aperture, true);
        check(&format!("heliar {name}, band by band"), &r);
    }
}

/// The Nikon zoom's default frame (fringed groups, two lights).
#[test]
#[ignore = "slow tier: the Nikon's fringed frame of two lights on lavapipe (a minute); by default \
            its splatted frame (`nikon_splatted`) and the Heliar's fringed ones"]
fn nikon_two_lights() {
    let r = record(
        "nikon-zoom-short",
        &["10,30", "4,200,0.5"],
        &Aperture::Circular,
        false,
    );
    check("nikon circle, two lights, fringed", &r);
}

/// The Nikon zoom's frame with an iris and with a mask (fringed, their outlines stepped over
/// τ). The default tier draws both apertures on the Heliar (`heliar_iris_and_mask`) and every
/// branch of the aperture shader on random attributes (`fringe_shader.rs`).
#[test]
#[ignore = "slow tier: two frames of a million triangles each on lavapipe (minutes)"]
fn nikon_iris_and_mask() {
    let r = record("nikon-zoom-short", &["10,30"], &iris(), false);
    assert!(has_aperture_fringes(&r), "nikon iris: fringed outlines");
    check("nikon iris, fringed", &r);
    let r = record("nikon-zoom-short", &["10,30"], &olf_mask(), false);
    assert!(has_aperture_fringes(&r), "nikon mask: fringed outlines");
    check("nikon mask, fringed", &r);
}

/// The Heliar's frame with two lights in it (one pattern shared, one of its own colour), drawn
/// band by band: the recording, the starbursts' splats, and the CPU image with the starbursts
/// added after the ghosts.
fn heliar_with_starbursts_scene() -> (FrameMeshes, Vec<StarburstSplat>, HdrImage) {
    use flarebench_sdk::ghost::GridTrace;
    use flarebench_sdk::starburst::{
        StarburstCache, StarburstLens, StarburstLight, StarburstSettings, StarburstSource,
        add_starburst,
    };
    let sys = load_lens("heliar-tronnier");
    let lights = ["8,60", "3,200,0.5,3200"];
    let recorded = record("heliar-tronnier", &lights, &Aperture::Circular, true);
    let (frame, _, _, _) = recorded.levels.clone().unwrap();
    let lens = StarburstLens::new(&sys).unwrap();
    let aperture = Aperture::Circular;
    let source = StarburstSource {
        aperture: &aperture,
        dust: None,
        settings: StarburstSettings {
            pupil_texels: 128,
            ..StarburstSettings::default()
        },
    };
    let mut cache = StarburstCache::new();
    let mut scratch = GridTrace::default();
    let splats: Vec<_> = lights
        .iter()
        .filter_map(|l| {
            let spec = LightSpec::parse(l).unwrap();
            let light = StarburstLight {
                theta_deg: spec.theta_deg,
                phi_deg: spec.phi_deg,
                intensity: spec.intensity,
                spectrum: spec.spectrum,
            };
            lens.place(&sys, &frame, &light, &source, &mut cache, &mut scratch)
                .unwrap()
                .1
        })
        .collect();
    assert_eq!(splats.len(), 2, "both lights are in the frame");
    let mut cpu = recorded.draw_cpu();
    let ghosts_only = cpu.luminance_sum();
    for s in &splats {
        add_starburst(
            &mut cpu,
            &frame,
            &s.pattern,
            s.centre_mm,
            s.f_number,
            s.flux,
        )
        .unwrap();
    }
    assert!(
        cpu.luminance_sum() > 2.0 * ghosts_only,
        "the starbursts dominate"
    );
    (recorded, splats, cpu)
}

/// Starbursts composited on the GPU from the patterns the CPU splats: two lights in the frame
/// (one pattern shared, one of its own colour), added after the ghosts.
#[test]
fn heliar_with_starbursts() {
    let (recorded, splats, cpu) = heliar_with_starbursts_scene();
    let img = gpu_image(&recorded, &splats, AccumFormat::F32, 0);
    assert!(!img.has_non_finite());
    let c = img.compare(&cpu).unwrap();
    eprintln!(
        "heliar with starbursts: rmse {:.2e}, energy {:.2e}",
        c.relative_rmse, c.energy_error
    );
    assert!(c.relative_rmse <= MAX_RMSE, "rmse {}", c.relative_rmse);
    assert!(
        c.energy_error.abs() <= MAX_ENERGY,
        "energy {}",
        c.energy_error
    );
}

// f16 accumulation (Rgba16Float targets) against f32 and the CPU: docs/gpu.md § Target format.

/// The largest finite f16.
const F16_MAX: f32 = 65504.0;

/// Per-value differences of an image against a reference, beyond the image-wide RMSE and
/// energy: what rounding to f16 does to single pixels.
#[derive(Clone, Copy, Debug, Default)]
struct ValueErrors {
    /// The largest `|a − b| / b` over channel values `b` of at least `floor`.
    worst: f64,
    /// The reference's largest value.
    reference_max: f32,
    /// Values of the image that are not finite or reach the largest f16.
    overflow: usize,
    /// Values the reference has (> 0) and the image has not (exactly 0)...
    lost: usize,
    /// ... and their share of the reference's energy.
    lost_energy: f64,
    /// The share of the reference's energy in values below the smallest normal f16 (2⁻¹⁴),
    /// where f16 has fewer than 11 significant bits.
    subnormal_energy: f64,
}

/// The exponent of the power of two that lifts `image`'s largest value to [2¹³, 2¹⁴): what an
/// f16 target holds with 4× headroom below its largest value (65504), the smallest values
/// reaching as far down its normal range as they can.
fn scale_for(image: &HdrImage) -> i32 {
    let max = image.max();
    assert!(max > 0.0 && max.is_finite());
    13 - max.log2().floor() as i32
}

/// `image` against `reference`; the worst relative error is taken over values of at least
/// `floor_share` of the reference's largest value.
fn value_errors(image: &HdrImage, reference: &HdrImage, floor_share: f32) -> ValueErrors {
    let reference_max = reference.max();
    let floor = floor_share * reference_max;
    let mut e = ValueErrors {
        reference_max,
        ..ValueErrors::default()
    };
    let (mut lost, mut total, mut subnormal) = (0.0_f64, 0.0_f64, 0.0_f64);
    for (p, q) in image.pixels.iter().zip(&reference.pixels) {
        for c in 0..3 {
            let (a, b) = (p[c], q[c]);
            total += f64::from(b);
            if b < 2.0_f32.powi(-14) {
                subnormal += f64::from(b);
            }
            if !a.is_finite() || a.abs() >= F16_MAX {
                e.overflow += 1;
            }
            if b > 0.0 && a == 0.0 {
                e.lost += 1;
                lost += f64::from(b);
            }
            if b >= floor && b > 0.0 {
                e.worst = e
                    .worst
                    .max((f64::from(a) - f64::from(b)).abs() / f64::from(b));
            }
        }
    }
    if total > 0.0 {
        e.lost_energy = lost / total;
        e.subnormal_energy = subnormal / total;
    }
    e
}

/// A 4 × 4 frame of one full-resolution level: a large triangle of irradiance `first` over
/// every pixel, then `n` more of `then`, drawn in that order.
fn stacked(first: f32, then: f32, n: usize) -> FrameMeshes {
    use flarebench_sdk::ghost::mesh::GhostMesh;
    use flarebench_sdk::image::CoarseGrid;
    use flarebench_sdk::raster::Coverage;
    let cover = |v: f32| {
        let mut m = GhostMesh::default();
        m.open.positions = vec![[-10.0, -10.0], [100.0, -10.0], [-10.0, 100.0]];
        m.open.attrs = vec![[v; 3]; 3];
        m.open.triangles = vec![[0, 1, 2]];
        m
    };
    let levels = (
        Frame::across_film(4, 4, 36.0),
        vec![CoarseGrid::for_frame(4, 4, 1)],
        Aperture::Circular,
        Coverage::Sampled { min_area: 0.5 },
    );
    let mut meshes = vec![(0, cover(first))];
    meshes.extend((0..n).map(|_| (0, cover(then))));
    FrameMeshes {
        levels: Some(levels),
        meshes,
    }
}

/// Why f16 loses the Nikon's energy: once a pixel's sum is large, an addition below half of
/// its last place (2⁻¹¹ relative) is rounded away whether the device rounds to nearest or
/// toward zero, however many there are. f32 keeps them.
#[test]
fn f16_sums_stall_under_small_additions() {
    let frame = stacked(1.0, 0.3 / 1024.0, 100);
    let f16 = gpu_image(&frame, &[], AccumFormat::F16, 0);
    let f32 = gpu_image(&frame, &[], AccumFormat::F32, 0);
    assert_eq!(f16.pixels[5], [1.0; 3], "the sum stays at 1 in f16");
    let expected = 1.0 + 100.0 * 0.3 / 1024.0;
    assert!(
        (f32.pixels[5][0] - expected).abs() < 1e-5,
        "{:?}",
        f32.pixels[5]
    );
}

/// f16 accumulation of the Heliar's frames at the scale that lifts them into f16's range,
/// within the bounds measured on lavapipe (docs/gpu.md § Target format): fringed, 2.0e-3 RMSE
/// and −1.8e-3 energy; band by band, 1.1e-2 and −9.0e-3, outside the 0.5% and 0.1%,
/// which is why the targets stay f32. Unscaled, the frame lies below f16's normal range and
/// nearly all of it is lost.
#[test]
#[ignore = "slow tier: four f16 frames on lavapipe for a target format left unused; by default \
            f16 with starbursts and the stalled sums"]
fn f16_heliar_circle_fringed_and_band_by_band() {
    for (name, band_by_band, max_rmse, max_energy) in [
        ("fringed", false, 3e-3, 2.5e-3),
        ("band by band", true, 1.5e-2, 1.2e-2),
    ] {
        let r = record(
            "heliar-tronnier",
            &["8,60"],
            &Aperture::Circular,
            band_by_band,
        );
        let cpu = r.draw_cpu();
        let k = scale_for(&cpu);
        let img = gpu_image(&r, &[], AccumFormat::F16, k);
        assert!(!img.has_non_finite(), "{name}: NaN or Inf in the f16 image");
        let c = img.compare(&cpu).unwrap();
        let e = value_errors(&img, &cpu, 0.01);
        eprintln!(
            "f16 heliar {name}, ×2^{k}: rmse {:.2e}, energy {:.2e}, worst {:.2e}",
            c.relative_rmse, c.energy_error, e.worst
        );
        assert_eq!((e.overflow, e.lost), (0, 0), "{name}: {e:?}");
        assert!(
            c.relative_rmse <= max_rmse,
            "{name}: rmse {}",
            c.relative_rmse
        );
        assert!(
            c.energy_error.abs() <= max_energy,
            "{name}: energy {}",
            c.energy_error
        );
        if !band_by_band {
            let raw = gpu_image(&r, &[], AccumFormat::F16, 0)
                .compare(&cpu)
                .unwrap();
            eprintln!(
                "f16 heliar {name}, unscaled: energy {:.2e}",
                raw.energy_error
            );
            assert!(raw.energy_error < -0.5, "energy {}", raw.energy_error);
        }
    }
}

/// f16 with two bright lights in the frame and their starbursts (the flux is scaled with the
/// ghosts): the starbursts hold most of the energy in few additions per pixel, so this frame
/// stays within the bounds (measured 4.8e-4 RMSE, −4.0e-4 energy), without overflow.
#[test]
fn f16_heliar_with_starbursts() {
    let (recorded, splats, cpu) = heliar_with_starbursts_scene();
    let k = scale_for(&cpu);
    let img = gpu_image(&recorded, &splats, AccumFormat::F16, k);
    assert!(!img.has_non_finite());
    let c = img.compare(&cpu).unwrap();
    let e = value_errors(&img, &cpu, 0.01);
    eprintln!(
        "f16 heliar with starbursts, ×2^{k}: rmse {:.2e}, energy {:.2e}, worst {:.2e}",
        c.relative_rmse, c.energy_error, e.worst
    );
    assert_eq!((e.overflow, e.lost), (0, 0), "{e:?}");
    assert!(c.relative_rmse <= 7e-4, "rmse {}", c.relative_rmse);
    assert!(c.energy_error.abs() <= 6e-4, "energy {}", c.energy_error);
}

/// The accumulation scale is a power of two, so in f32 it changes nothing: the image read
/// back and the tone-mapped bytes are the same at 2^20 as at 1.
#[test]
fn f32_scale_is_exact() {
    let r = record("heliar-tronnier", &["8,60"], &Aperture::Circular, false);
    let render = |k: i32| {
        let mut gpu = GhostRenderer::new(context(), AccumFormat::F32).unwrap();
        gpu.set_scale_log2(k);
        r.replay(&mut gpu);
        let bytes = gpu.tone_map(22.0, flarebench_gpu::ToneCurve::Aces).unwrap();
        (gpu.read_back().unwrap(), bytes)
    };
    let (a, a_bytes) = render(0);
    let (b, b_bytes) = render(20);
    assert!(a.luminance_sum() > 0.0);
    assert!(a.pixels == b.pixels, "the scaled image differs");
    assert!(
        a_bytes.iter().any(|&v| v > 0),
        "the tone-mapped frame is black"
    );
    assert!(a_bytes == b_bytes, "the scaled tone-mapped bytes differ");
}

/// The measurement behind docs/gpu.md's f16 table: every parity frame accumulated in f32 and
/// in f16, each against the CPU image, and f16 against f32 (the same triangles and edge
/// rules, so only the accumulation differs). Slow on lavapipe; run it in release:
/// `cargo test --release -p flarebench-gpu --test parity -- --ignored --nocapture f16_table`.
#[test]
#[ignore = "a measurement for docs/gpu.md (minutes on lavapipe), not a check"]
fn f16_table() {
    // 1 + 0.75 of its last place: to nearest gives the next f16 up, toward zero gives 1.
    let probe = gpu_image(&stacked(1.0, 0.75 / 1024.0, 1), &[], AccumFormat::F16, 0);
    let rounding = if probe.pixels[5][0] > 1.0 {
        "to nearest"
    } else {
        "toward zero"
    };
    eprintln!("f16 blending on this device rounds {rounding}");
    let mut frames: Vec<(&str, FrameMeshes, Vec<StarburstSplat>, Option<HdrImage>)> = vec![
        (
            "Heliar 8°,60°, circle, fringed",
            record("heliar-tronnier", &["8,60"], &Aperture::Circular, false),
            Vec::new(),
            None,
        ),
        (
            "Heliar, circle, band by band",
            record("heliar-tronnier", &["8,60"], &Aperture::Circular, true),
            Vec::new(),
            None,
        ),
        (
            "Heliar, iris",
            record("heliar-tronnier", &["8,60"], &iris(), true),
            Vec::new(),
            None,
        ),
        (
            "Heliar, mask",
            record("heliar-tronnier", &["8,60"], &olf_mask(), true),
            Vec::new(),
            None,
        ),
    ];
    let (r, splats, cpu) = heliar_with_starbursts_scene();
    frames.push(("Heliar, two lights, starbursts", r, splats, Some(cpu)));
    for (name, lights, aperture) in [
        (
            "Nikon 10°,30° + 4°,200°, circle, fringed",
            &["10,30", "4,200,0.5"][..],
            Aperture::Circular,
        ),
        ("Nikon, iris", &["10,30"][..], iris()),
        ("Nikon, mask", &["10,30"][..], olf_mask()),
    ] {
        let r = record("nikon-zoom-short", lights, &aperture, false);
        frames.push((name, r, Vec::new(), None));
    }
    eprintln!(
        "| frame | triangles | max | k | f32 rmse | f32 energy | f32 worst | f16 (k = 0) rmse | \
         f16 (k = 0) energy | f16 rmse | f16 energy | f16 worst | f16/f32 rmse | f16/f32 energy | \
         f16/f32 worst | overflow | lost (f32) | lost energy | subnormal energy (k = 0) |"
    );
    for (name, recorded, splats, cpu) in frames {
        let cpu = cpu.unwrap_or_else(|| recorded.draw_cpu());
        let k = scale_for(&cpu);
        let f32_img = gpu_image(&recorded, &splats, AccumFormat::F32, 0);
        let raw = gpu_image(&recorded, &splats, AccumFormat::F16, 0);
        let f16_img = gpu_image(&recorded, &splats, AccumFormat::F16, k);
        let (a, r, b, d) = (
            f32_img.compare(&cpu).unwrap(),
            raw.compare(&cpu).unwrap(),
            f16_img.compare(&cpu).unwrap(),
            f16_img.compare(&f32_img).unwrap(),
        );
        let (ea, eb, ed) = (
            value_errors(&f32_img, &cpu, 0.01),
            value_errors(&f16_img, &cpu, 0.01),
            value_errors(&f16_img, &f32_img, 0.01),
        );
        eprintln!(
            "| {name} | {} | {:.3e} | {k} | {:.1e} | {:.1e} | {:.1e} | {:.1e} | {:.1e} | {:.1e} | \
             {:.1e} | {:.1e} | {:.1e} | {:.1e} | {:.1e} | {} | {} ({}) | {:.1e} | {:.1e} |",
            recorded.triangles(),
            ea.reference_max,
            a.relative_rmse,
            a.energy_error,
            ea.worst,
            r.relative_rmse,
            r.energy_error,
            b.relative_rmse,
            b.energy_error,
            eb.worst,
            d.relative_rmse,
            d.energy_error,
            ed.worst,
            eb.overflow,
            eb.lost,
            ea.lost,
            eb.lost_energy,
            ea.subnormal_energy,
        );
        if !splats.is_empty() {
            // 16× more than the scale allows: the starburst's core beyond 65504.
            let over = gpu_image(&recorded, &splats, AccumFormat::F16, k + 4);
            let lifted = 2.0_f32.powi(k + 4);
            let values = || over.pixels.iter().flatten();
            let beyond = values().filter(|v| (*v * lifted).abs() >= F16_MAX).count();
            let infinite = values().filter(|v| v.is_infinite()).count();
            let cpu_beyond = cpu
                .pixels
                .iter()
                .flatten()
                .filter(|v| (*v * lifted).abs() >= F16_MAX)
                .count();
            eprintln!(
                "{name} at 2^{}: {cpu_beyond} CPU values beyond 65504 there; the f16 image has \
                 {beyond} at or beyond it, {infinite} infinite",
                k + 4
            );
        }
    }
}
