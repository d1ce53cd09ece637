//! The plugin host against real plugin libraries: the guide's example plugin
//! (`algorithms/example-glow`, built by `cargo build --workspace`), a plugin that misbehaves on
//! request (`tests/plugins/faulty`), and hand-written headers compiled here with `rustc`
//! (`tests/plugins/misfit.rs`): every fault is a clear, typed error and the host carries on.

use std::path::{Path, PathBuf};
use std::process::Command;

use flarebench_sdk::abi::author::{PluginKind, Scene, SceneLight};
use flarebench_sdk::abi::host::{self, LoadedPlugin, PluginCallError, PluginLoadError};
use flarebench_sdk::abi::params::{ParamKind, defaults, parse_values};
use flarebench_sdk::aperture::{Aperture, ApertureMask};
use flarebench_sdk::color::LightSpectrum;
use flarebench_sdk::frame::Frame;
use flarebench_sdk::paraxial::analyse;
use flarebench_sdk::spectrum::LAMBDA_D_NM;
use flarebench_test_support::{build_dir, library_file_name, load_lens, plugin_library};

fn scene(width: usize, height: usize, film_width_mm: f64, theta: f64, phi: f64) -> Scene {
    Scene {
        lights: vec![SceneLight {
            theta_deg: theta,
            phi_deg: phi,
            intensity: 2.0,
            spectrum: LightSpectrum::D65,
        }],
        frame: Frame {
            width,
            height,
            film_width_mm,
            film_height_mm: film_width_mm * height as f64 / width as f64,
        },
        aperture: Aperture::Circular,
    }
}

fn faulty() -> LoadedPlugin {
    host::load(&plugin_library("flarebench_test_plugin_faulty")).unwrap()
}

fn values(p: &LoadedPlugin, text: &str) -> Vec<f64> {
    parse_values(&p.params, text).unwrap()
}

/// Energy and centroid of an image's first channel.
fn energy_and_centroid(img: &flarebench_sdk::image::HdrImage) -> (f64, f64, f64) {
    let (mut e, mut sx, mut sy) = (0.0, 0.0, 0.0);
    for (k, p) in img.pixels.iter().enumerate() {
        let v = p[0] as f64;
        e += v;
        sx += v * ((k % img.width) as f64 + 0.5);
        sy += v * ((k / img.width) as f64 + 0.5);
    }
    (e, sx / e, sy / e)
}

#[test]
fn the_example_plugin_library_loads_and_describes_itself() {
    let p = host::load(&plugin_library("example_glow")).unwrap();
    assert_eq!(p.name, "example-glow");
    assert_eq!(p.kind, PluginKind::Other);
    assert_eq!((p.abi_major, p.abi_minor), (1, 1));
    assert!(p.rustc_version.starts_with("rustc "), "{}", p.rustc_version);
    let names: Vec<&str> = p.params.iter().map(|q| q.name.as_str()).collect();
    assert_eq!(names, ["sigma_px", "gain"]);
    assert_eq!(p.params[0].kind, ParamKind::Float);
    assert_eq!(defaults(&p.params), vec![8.0, 1.0]);
}

/// Sum of a Gaussian of σ = 3 px sampled at pixel centres, 20σ from every edge: its energy to
/// within f32 summation (measured 2e-7); the centroid of the samples is the centre to 1e-6 px.
const GLOW_ENERGY_TOL: f64 = 1e-5;
const GLOW_CENTROID_TOL_PX: f64 = 1e-3;
/// Sum of a 16 × 8 f32 image (every pixel 0.5 plus a triangle of 4): f32 rounding of the pixels
/// and the sum.
const IMAGE_SUM_TOL: f64 = 1e-4;

#[test]
fn the_example_glow_puts_gain_times_intensity_at_the_lights_paraxial_image() {
    let p = host::load(&plugin_library("example_glow")).unwrap();
    let lens = load_lens("heliar-tronnier");
    let efl = analyse(&lens, LAMBDA_D_NM).unwrap().efl_mm;
    let mut inst = p.instantiate().unwrap();
    inst.prepare(&lens).unwrap();
    // Light 3° off axis at azimuth 90°: its rays tilt toward -x (`Ray::collimated`), so the
    // image lies at x = +EFL tan 3° on the sensor, left of the centre in the photograph
    // (`Frame::to_pixel`: sensor x grows to the left).
    let s = scene(400, 300, 36.0, 3.0, 90.0);
    let out = inst.render(&s, &values(&p, "sigma_px=3,gain=1.5")).unwrap();
    assert_eq!(out.items_drawn, 1);
    let (e, cx, cy) = energy_and_centroid(&out.image);
    assert!((e / 3.0 - 1.0).abs() < GLOW_ENERGY_TOL, "energy {e}");
    let px_mm = 36.0 / 400.0;
    let expect_x = 200.0 - efl * 3f64.to_radians().tan() / px_mm;
    assert!(
        (cx - expect_x).abs() < GLOW_CENTROID_TOL_PX,
        "x {cx} vs {expect_x}"
    );
    assert!((cy - 150.0).abs() < GLOW_CENTROID_TOL_PX, "y {cy}");
}

#[test]
fn a_well_behaved_render_adds_its_image_and_its_rasterized_mesh() {
    let p = faulty();
    let mut inst = p.instantiate().unwrap();
    inst.prepare(&load_lens("heliar-tronnier")).unwrap();
    let s = scene(16, 8, 36.0, 1.0, 0.0);
    let out = inst.render(&s, &values(&p, "level=0.5,mesh=true")).unwrap();
    // Every pixel 0.5, plus the triangle: area 8 px² × radiance 0.5 = 4, per channel.
    let sum = out.image.sum();
    for c in sum {
        assert!((c - (0.5 * 128.0 + 4.0)).abs() < IMAGE_SUM_TOL, "{sum:?}");
    }
    assert_eq!(out.mesh_triangles, 1);
}

#[test]
fn a_plugin_error_is_reported_and_the_instance_keeps_working() {
    let p = faulty();
    let mut inst = p.instantiate().unwrap();
    inst.prepare(&load_lens("heliar-tronnier")).unwrap();
    let s = scene(8, 8, 36.0, 1.0, 0.0);
    let e = inst.render(&s, &values(&p, "fault=error")).unwrap_err();
    assert!(matches!(e, PluginCallError::Failed { .. }), "{e:?}");
    assert_eq!(
        e.to_string(),
        "plugin `test-faulty` failed in render: asked to fail"
    );
    assert!(inst.render(&s, &values(&p, "")).is_ok());
}

#[test]
fn a_panic_in_render_is_caught_and_only_that_instance_is_discarded() {
    let p = faulty();
    let lens = load_lens("heliar-tronnier");
    let mut inst = p.instantiate().unwrap();
    inst.prepare(&lens).unwrap();
    let s = scene(8, 8, 36.0, 1.0, 0.0);
    let e = inst
        .render(&s, &values(&p, "fault=panic_render"))
        .unwrap_err();
    assert!(matches!(e, PluginCallError::Panicked { .. }), "{e:?}");
    assert!(e.to_string().contains("asked to panic in render"), "{e}");
    let again = inst.render(&s, &values(&p, "")).unwrap_err();
    assert!(
        matches!(again, PluginCallError::Poisoned { .. }),
        "{again:?}"
    );
    drop(inst);
    // The host and the library carry on: a new instance renders.
    let mut fresh = p.instantiate().unwrap();
    fresh.prepare(&lens).unwrap();
    assert!(fresh.render(&s, &values(&p, "")).is_ok());
}

#[test]
fn a_panic_in_prepare_is_caught() {
    let p = faulty();
    let mut lens = load_lens("heliar-tronnier");
    lens.name = "panic-in-prepare".into();
    let mut inst = p.instantiate().unwrap();
    let e = inst.prepare(&lens).unwrap_err();
    assert!(
        matches!(
            e,
            PluginCallError::Panicked {
                call: "prepare",
                ..
            }
        ),
        "{e:?}"
    );
}

#[test]
fn nan_or_infinite_pixels_are_an_error_naming_the_first() {
    let p = faulty();
    let mut inst = p.instantiate().unwrap();
    inst.prepare(&load_lens("heliar-tronnier")).unwrap();
    let s = scene(8, 8, 36.0, 1.0, 0.0);
    let e = inst.render(&s, &values(&p, "fault=nan")).unwrap_err();
    match &e {
        PluginCallError::NonFinite { count, x, y, .. } => assert_eq!((*count, *x, *y), (1, 1, 1)),
        other => panic!("{other:?}"),
    }
    assert!(e.to_string().contains("non-finite"), "{e}");
    let e = inst.render(&s, &values(&p, "fault=inf")).unwrap_err();
    assert!(
        matches!(e, PluginCallError::NonFinite { x: 0, y: 0, .. }),
        "{e:?}"
    );
    assert!(inst.render(&s, &values(&p, "")).is_ok());
}

#[test]
fn render_into_resizes_and_clears_the_callers_buffer() {
    let p = faulty();
    let mut inst = p.instantiate().unwrap();
    inst.prepare(&load_lens("heliar-tronnier")).unwrap();
    let v = values(&p, "level=0.25");
    let small = scene(8, 6, 36.0, 1.0, 0.0);
    let fresh = inst.render(&small, &v).unwrap().image;
    // A dirty buffer of another size, as left by an earlier frame.
    let mut buffer = flarebench_sdk::image::HdrImage::new(20, 20);
    buffer.pixels.iter_mut().for_each(|p| *p = [7.0; 3]);
    let stats = inst.render_into(&small, &v, &mut buffer).unwrap();
    assert_eq!(buffer, fresh);
    assert_eq!(stats.mesh_triangles, 0);
    // And again into the same buffer: the same image, not twice the light.
    inst.render_into(&small, &v, &mut buffer).unwrap();
    assert_eq!(buffer, fresh);
}

#[test]
fn a_mesh_indexing_past_its_vertices_is_an_error() {
    let p = faulty();
    let mut inst = p.instantiate().unwrap();
    inst.prepare(&load_lens("heliar-tronnier")).unwrap();
    let e = inst
        .render(&scene(8, 8, 36.0, 1.0, 0.0), &values(&p, "fault=bad_mesh"))
        .unwrap_err();
    assert!(matches!(e, PluginCallError::BadMesh { .. }), "{e:?}");
}

#[test]
fn out_of_range_values_are_refused_by_the_plugin_side_too() {
    let p = faulty();
    let mut inst = p.instantiate().unwrap();
    inst.prepare(&load_lens("heliar-tronnier")).unwrap();
    // Bypassing parse_values: the thunk checks ranges itself.
    let e = inst
        .render(&scene(8, 8, 36.0, 1.0, 0.0), &[0.0, 99.0, 0.0])
        .unwrap_err();
    assert!(
        matches!(e, PluginCallError::InvalidArgument { .. }),
        "{e:?}"
    );
    assert!(e.to_string().contains("`level`"), "{e}");
    let e = inst
        .render(&scene(8, 8, 36.0, 1.0, 0.0), &[0.0])
        .unwrap_err();
    assert!(e.to_string().contains("1 parameter values for 3"), "{e}");
}

/// A 16 × 16 mask: a disc of radius 6 texels, open inside.
fn disc_mask() -> Aperture {
    let luma: Vec<u8> = (0..256)
        .map(|k| {
            let (x, y) = ((k % 16) as f64 - 7.5, (k / 16) as f64 - 7.5);
            if x * x + y * y < 36.0 { 255 } else { 0 }
        })
        .collect();
    Aperture::Mask(ApertureMask::from_luma(16, 16, &luma).unwrap())
}

#[test]
fn an_abi_1_1_plugin_takes_a_mask_and_rgb_and_flat_lights() {
    let p = faulty();
    assert_eq!(p.abi_minor, 1);
    let mut inst = p.instantiate().unwrap();
    inst.prepare(&load_lens("heliar-tronnier")).unwrap();
    let mut s = scene(8, 8, 36.0, 1.0, 0.0);
    s.aperture = disc_mask();
    s.lights[0].spectrum = LightSpectrum::Rgb([1.0, 0.5, 0.2]);
    s.lights.push(SceneLight {
        spectrum: LightSpectrum::Flat,
        ..s.lights[0].clone()
    });
    let out = inst.render(&s, &values(&p, "level=0.5")).unwrap();
    assert_eq!(out.image.sum(), [32.0; 3]);
}

#[test]
fn a_bad_light_colour_is_refused_by_the_plugin_side_and_the_instance_keeps_working() {
    let p = faulty();
    let mut inst = p.instantiate().unwrap();
    inst.prepare(&load_lens("heliar-tronnier")).unwrap();
    let mut s = scene(8, 8, 36.0, 1.0, 0.0);
    // The host sends what it is given; the thunk checks it.
    s.lights[0].spectrum = LightSpectrum::Rgb([f32::NAN, 0.5, 0.2]);
    let e = inst.render(&s, &values(&p, "")).unwrap_err();
    assert!(
        matches!(e, PluginCallError::InvalidArgument { call: "render", .. }),
        "{e:?}"
    );
    assert!(e.to_string().contains("light 0: light colour"), "{e}");
    s.lights[0].spectrum = LightSpectrum::Rgb([0.2, 0.5, 1.0]);
    assert!(inst.render(&s, &values(&p, "")).is_ok());
}

/// Compiles `tests/plugins/misfit.rs` as a shared library with `rustc` (it has no
/// dependencies), with `variant` set and the panic strategy given.
///
/// Each variant is compiled once per test process, under a lock, into a folder of its own:
/// tests run in parallel, and two rustc runs writing the same variant's object files (or one
/// overwriting a library another test has loaded) would break each other.
fn misfit(variant: Option<&str>, panic: &str) -> PathBuf {
    static BUILT: std::sync::Mutex<Vec<(String, PathBuf)>> = std::sync::Mutex::new(Vec::new());
    let stem = format!("misfit_{}_{panic}", variant.unwrap_or("ok"));
    let mut built = BUILT.lock().unwrap_or_else(|e| e.into_inner());
    if let Some((_, path)) = built.iter().find(|(s, _)| *s == stem) {
        return path.clone();
    }
    let dir = build_dir().join("misfit-plugins").join(&stem);
    std::fs::create_dir_all(&dir).unwrap();
    let out = dir.join(library_file_name(&stem));
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("plugins/misfit.rs");
    let rustc = std::env::var("RUSTC").unwrap_or_else(|_| "rustc".into());
    let mut cmd = Command::new(rustc);
    cmd.args([
        "--edition",
        "2024",
        "--crate-type",
        "cdylib",
        "--crate-name",
        &stem,
    ])
    .args(["-C", &format!("panic={panic}"), "-o"])
    .arg(&out)
    .arg(&src);
    if let Some(v) = variant {
        cmd.args(["--cfg", &format!("variant=\"{v}\"")]);
    }
    let o = cmd.output().expect("rustc runs");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    built.push((stem, out.clone()));
    out
}

#[test]
fn hand_written_headers_load_or_fail_with_the_reason() {
    // The well-formed one loads: the host speaks the C ABI, not only the sdk's macro.
    let ok = host::load(&misfit(None, "unwind")).unwrap();
    assert_eq!(ok.name, "misfit");
    let mut inst = ok.instantiate().unwrap();
    assert!(inst.prepare(&load_lens("heliar-tronnier")).is_ok());
    drop(inst);

    let e = host::load(&misfit(Some("bad_magic"), "unwind")).unwrap_err();
    assert!(matches!(e, PluginLoadError::BadMagic { .. }), "{e:?}");
    assert!(
        e.to_string().contains("not a flarebench plugin header"),
        "{e}"
    );

    let e = host::load(&misfit(Some("wrong_major"), "unwind")).unwrap_err();
    assert!(
        matches!(e, PluginLoadError::AbiMajor { major: 2, .. }),
        "{e:?}"
    );
    assert!(e.to_string().contains("built for plugin ABI 2.0"), "{e}");

    let e = host::load(&misfit(Some("short_struct"), "unwind")).unwrap_err();
    assert!(
        matches!(
            e,
            PluginLoadError::ShortHeader {
                size: 104,
                needed: 152,
                ..
            }
        ),
        "{e:?}"
    );

    let e = host::load(&misfit(None, "abort")).unwrap_err();
    assert!(matches!(e, PluginLoadError::PanicAbort { .. }), "{e:?}");
    assert!(e.to_string().contains("panic = \"unwind\""), "{e}");
}

#[test]
fn an_abi_1_0_plugin_is_refused_a_mask_or_an_rgb_light_and_still_renders_the_rest() {
    // misfit's header says ABI 1.0: it knows neither the mask nor light_ext.
    let p = host::load(&misfit(None, "unwind")).unwrap();
    assert_eq!((p.abi_major, p.abi_minor), (1, 0));
    let mut inst = p.instantiate().unwrap();
    inst.prepare(&load_lens("heliar-tronnier")).unwrap();
    let circle = scene(8, 8, 36.0, 1.0, 0.0);

    let mut masked = circle.clone();
    masked.aperture = disc_mask();
    let e = inst.render(&masked, &[]).unwrap_err();
    assert!(matches!(e, PluginCallError::Unsupported { .. }), "{e:?}");
    assert_eq!(
        e.to_string(),
        "plugin `misfit`: an aperture mask image needs plugin ABI 1.1, but the plugin was \
         built for ABI 1.0 (sdk hand-written); rebuild it against this sdk"
    );

    let mut coloured = circle.clone();
    coloured.lights.push(SceneLight {
        spectrum: LightSpectrum::Rgb([1.0, 0.5, 0.2]),
        ..coloured.lights[0].clone()
    });
    let e = inst.render(&coloured, &[]).unwrap_err();
    assert!(matches!(e, PluginCallError::Unsupported { .. }), "{e:?}");
    let text = e.to_string();
    assert!(
        text.contains("light 1's spectrum Rgb([1.0, 0.5, 0.2]) needs plugin ABI 1.1")
            && text.contains("built for ABI 1.0"),
        "{text}"
    );
    coloured.lights[1].spectrum = LightSpectrum::Flat;
    assert!(matches!(
        inst.render(&coloured, &[]),
        Err(PluginCallError::Unsupported { .. })
    ));

    // What 1.0 can say still goes through: a circle, an iris, D65 and blackbody lights.
    assert!(inst.render(&circle, &[]).is_ok());
    let mut iris = circle.clone();
    iris.aperture = Aperture::Iris {
        blades: 6,
        rotation_rad: 0.0,
        roundness: 0.0,
    };
    iris.lights[0].spectrum = LightSpectrum::Blackbody { kelvin: 3200.0 };
    assert!(inst.render(&iris, &[]).is_ok());
}

#[test]
fn a_file_that_is_not_a_library_gives_the_loaders_own_reason() {
    let dir = build_dir().join("misfit-plugins");
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("libnot_a_library.so");
    std::fs::write(&path, "this is text").unwrap();
    let e = host::load(&path).unwrap_err();
    assert!(matches!(e, PluginLoadError::Open { .. }), "{e:?}");
    let text = e.to_string();
    // libloading's own text is only "dlopen failed"; the detail from its source names the
    // file and what is wrong with it.
    assert!(
        text.len() > text.find("could not load").unwrap() + 40,
        "{text}"
    );
    let e = host::load(&dir.join("libmissing.so")).unwrap_err();
    assert!(matches!(e, PluginLoadError::Open { .. }), "{e:?}");
    // A library without the entry symbol.
    let e = host::load(&misfit_no_entry(&dir)).unwrap_err();
    assert!(matches!(e, PluginLoadError::NoEntry { .. }), "{e:?}");
}

#[test]
fn a_fresh_copy_loads_beside_the_original_renders_the_same_and_leaves_no_file() {
    let path = plugin_library("example_glow");
    let original = host::load(&path).unwrap();
    let copies: Vec<LoadedPlugin> = (0..2)
        .map(|_| host::load_fresh_copy(&path).unwrap())
        .collect();
    let lens = load_lens("heliar-tronnier");
    let s = scene(120, 80, 36.0, 2.0, 30.0);
    let render = |p: &LoadedPlugin| {
        let mut inst = p.instantiate().unwrap();
        inst.prepare(&lens).unwrap();
        inst.render(&s, &values(p, "sigma_px=4")).unwrap().image
    };
    // Instances of the original and of both copies live at once.
    let first = render(&original);
    for c in &copies {
        assert_eq!(c.path, path, "a copy is named by its original");
        assert_eq!(c.name, "example-glow");
        assert!(render(c).pixels == first.pixels);
    }
    // The copies' files are removed once loaded (the mappings keep them).
    #[cfg(unix)]
    {
        let dir =
            std::env::temp_dir().join(format!("flarebench-plugin-copies-{}", std::process::id()));
        let left: Vec<_> = std::fs::read_dir(&dir).unwrap().flatten().collect();
        assert!(left.is_empty(), "{left:?}");
    }
    // A copy that cannot be loaded is an error about the original file.
    let dir = build_dir().join("misfit-plugins");
    std::fs::create_dir_all(&dir).unwrap();
    let bad = dir.join("libfresh_garbage.so");
    std::fs::write(&bad, "not a library").unwrap();
    let e = host::load_fresh_copy(&bad).unwrap_err();
    assert!(matches!(e, PluginLoadError::Open { .. }), "{e:?}");
    assert_eq!(e.path(), bad);
    assert!(e.to_string().starts_with(bad.to_str().unwrap()), "{e}");
    let e = host::load_fresh_copy(&dir.join("libmissing.so")).unwrap_err();
    assert!(matches!(e, PluginLoadError::Copy { .. }), "{e:?}");
}

/// A shared library that exports nothing of ours.
fn misfit_no_entry(dir: &Path) -> PathBuf {
    let src = dir.join("no_entry.rs");
    std::fs::write(
        &src,
        "#[unsafe(no_mangle)] pub extern \"C\" fn something_else() {}\n",
    )
    .unwrap();
    let out = dir.join(library_file_name("no_entry"));
    let rustc = std::env::var("RUSTC").unwrap_or_else(|_| "rustc".into());
    let o = Command::new(rustc)
        .args(["--edition", "2024", "--crate-type", "cdylib", "-o"])
        .arg(&out)
        .arg(&src)
        .output()
        .expect("rustc runs");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    out
}

#[test]
fn the_guide_shows_the_example_crate_verbatim() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let guide = std::fs::read_to_string(root.join("docs/plugins.md")).unwrap();
    for file in [
        "algorithms/example-glow/src/lib.rs",
        "algorithms/example-glow/Cargo.toml",
    ] {
        let text = std::fs::read_to_string(root.join(file)).unwrap();
        assert!(
            guide.contains(&text),
            "docs/plugins.md no longer shows {file} as it is"
        );
    }
}
