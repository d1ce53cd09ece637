//! The fringe shader's WGSL port (`shaders/fringe.wgsl`, `flarebench_gpu::fringe`) shades as
//! the CPU's `FringeShader::shade` does: run in a compute shader, one invocation per attribute
//! vector, on (a) attributes inside the fringed triangles of real meshes (the Heliar's
//! dispersive ghosts, many on the clip's and the stop's edges) and (b) random valid
//! attributes that take every branch of the shader.

use std::sync::{Arc, OnceLock};

use flarebench_gpu::fringe::{APERTURE_SHADER, SHADER, aperture_bindings, pack_tables};
use flarebench_gpu::{AdapterChoice, GpuContext};
use flarebench_sdk::aperture::Aperture;
use flarebench_sdk::frame::Frame;
use flarebench_sdk::ghost::fringe::{APERTURE_FLAG, FringeAttrs, FringeShader};
use flarebench_sdk::ghost::fringe_table::FringeTable;
use flarebench_sdk::ghost::sink::FrameMeshes;
use flarebench_sdk::raster::Shader;
use flarebench_test_support::load_lens;
use ghost_raytrace::ghosts::{self, RenderOptions};
use ghost_raytrace::plan::{self, PlanOptions};
use ghost_raytrace::scene::{LightSpec, Quality};

/// Largest difference per channel between the GPU's and the CPU's shade, in units of the
/// vector's irradiance (its largest RGB channel), on top of [`EDGE_TOLERANCE`], wherever the
/// GPU follows the CPU's f32 arithmetic (every way but the wide ends' exact integral).
/// Measured on lavapipe: 0 (bit for bit) on the Heliar's meshes and on the random vectors.
const TOLERANCE: f32 = 1e-6;

/// The same for a wide end integrated exactly (`smooth_share`): the CPU sums a cubic's
/// coefficients (up to a few hundred) times f32 partial moments in f64, the GPU the
/// smoothstep's mean per table interval in f32. Measured on lavapipe (two seeds): 1.3e-5 on
/// the Heliar's meshes, 1.5e-5 to 1.7e-5 on the random vectors — the CPU's own error: against
/// an f64 oracle the CPU is off by as much, the GPU by at most 2.0e-6
/// ([`WIDE_ORACLE_TOLERANCE`]).
const WIDE_TOLERANCE: f32 = 1e-4;

/// Largest difference of the GPU's open share from the f64 oracle ([`wide_oracle`]) on a wide
/// end integrated exactly. Measured on lavapipe (two seeds): 1.9e-6 to 2.0e-6 on the Heliar's
/// meshes, 4.4e-7 on the random vectors.
const WIDE_ORACLE_TOLERANCE: f64 = 1e-5;

/// A further allowance where the shade is steep: the feather's smoothstep moves the whole
/// irradiance over a width `f` of the clip radius, so an f32 rounding of a radius near 1
/// (`2⁻²⁴`, where a GPU fuses a multiply and an add the CPU rounds twice, or its square root
/// is a rounding off) moves the shade by up to `1.5 · 2⁻²⁴ / f`. Allowed: that many such
/// roundings, per unit irradiance. Measured on lavapipe: none needed (it neither fuses nor
/// rounds differently).
const EDGE_TOLERANCE: f32 = 4.0;

/// Largest difference per channel between the GPU's and the CPU's shade, in units of the
/// vector's irradiance, on vectors flagged for an aperture other than the circle
/// (`APERTURE_FLAG`): the CPU takes the iris's signed distance in f64, the GPU in f32, and
/// the mask's decision whether the whole segment is open (`uniform_around`) may fall the
/// other way where it is on its margin (the clip's analytic share against the stepped one).
/// Measured on lavapipe: 2.3e-4 (iris) and 2.0e-5 (mask) on 50 000 random vectors each.
const APERTURE_TOLERANCE: f32 = 1e-3;

/// The compute entry point run with `fringe.wgsl`: attribute vector `i` in, its RGB and the
/// branch it took (`fringe_branch`) out.
const HARNESS: &str = r"
@group(0) @binding(0) var<storage, read> harness_in: array<f32>;
@group(0) @binding(1) var<storage, read_write> harness_out: array<f32>;

@compute @workgroup_size(64)
fn harness_main(@builtin(global_invocation_id) id: vec3<u32>,
                @builtin(num_workgroups) groups: vec3<u32>) {
    let i = id.x + id.y * groups.x * 64u;
    if i >= arrayLength(&harness_in) / 12u {
        return;
    }
    var a: array<f32, 12>;
    for (var k = 0u; k < 12u; k++) {
        a[k] = harness_in[12u * i + k];
    }
    let s = fringe_shade(a);
    harness_out[4u * i] = s.x;
    harness_out[4u * i + 1u] = s.y;
    harness_out[4u * i + 2u] = s.z;
    harness_out[4u * i + 3u] = f32(fringe_branch);
}
";

fn context() -> Arc<GpuContext> {
    static CTX: OnceLock<Arc<GpuContext>> = OnceLock::new();
    CTX.get_or_init(|| Arc::new(GpuContext::new(AdapterChoice::Any).expect("a GPU adapter")))
        .clone()
}

fn storage(read_only: bool, binding: u32) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Storage { read_only },
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}

/// The GPU's shade of each of `attrs` with `tables` and `aperture`, and the branch it took.
fn gpu_shade(
    tables: &[FringeTable],
    attrs: &[FringeAttrs],
    aperture: &Aperture,
) -> Vec<([f32; 3], u32)> {
    use wgpu::util::DeviceExt;
    let ctx = context();
    let device = &ctx.device;
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("fringe harness"),
        source: wgpu::ShaderSource::Wgsl(format!("{APERTURE_SHADER}\n{SHADER}\n{HARNESS}").into()),
    });
    let io_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("harness io"),
        entries: &[
            storage(true, 0),
            storage(false, 1),
            wgpu::BindGroupLayoutEntry {
                binding: 4,
                visibility: wgpu::ShaderStages::COMPUTE,
                ty: wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Uniform,
                    has_dynamic_offset: false,
                    min_binding_size: None,
                },
                count: None,
            },
            storage(true, 5),
        ],
    });
    let table_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("fringe tables"),
        entries: &[storage(true, 0)],
    });
    let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some("fringe harness"),
        bind_group_layouts: &[Some(&io_layout), Some(&table_layout)],
        immediate_size: 0,
    });
    let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some("fringe harness"),
        layout: Some(&layout),
        module: &module,
        entry_point: Some("harness_main"),
        compilation_options: Default::default(),
        cache: None,
    });
    let input: Vec<f32> = attrs.iter().flatten().copied().collect();
    let input_buf = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("harness in"),
        contents: bytemuck::cast_slice(&input),
        usage: wgpu::BufferUsages::STORAGE,
    });
    let out_bytes = (attrs.len() * 16) as u64;
    let output = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("harness out"),
        size: out_bytes,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    });
    let readback = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("harness readback"),
        size: out_bytes,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let (block, fields) = aperture_bindings(aperture);
    let block_buf = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("aperture block"),
        contents: &block,
        usage: wgpu::BufferUsages::UNIFORM,
    });
    let fields_buf = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("mask fields"),
        contents: bytemuck::cast_slice(&fields),
        usage: wgpu::BufferUsages::STORAGE,
    });
    let table_buf = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("fringe tables"),
        contents: bytemuck::cast_slice(&pack_tables(tables)),
        usage: wgpu::BufferUsages::STORAGE,
    });
    let io_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("harness io"),
        layout: &io_layout,
        entries: &[
            wgpu::BindGroupEntry {
                binding: 0,
                resource: input_buf.as_entire_binding(),
            },
            wgpu::BindGroupEntry {
                binding: 1,
                resource: output.as_entire_binding(),
            },
            wgpu::BindGroupEntry {
                binding: 4,
                resource: block_buf.as_entire_binding(),
            },
            wgpu::BindGroupEntry {
                binding: 5,
                resource: fields_buf.as_entire_binding(),
            },
        ],
    });
    let table_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("fringe tables"),
        layout: &table_layout,
        entries: &[wgpu::BindGroupEntry {
            binding: 0,
            resource: table_buf.as_entire_binding(),
        }],
    });
    let groups = attrs.len().div_ceil(64) as u32;
    let (gx, gy) = (groups.min(32_768), groups.div_ceil(32_768));
    let mut encoder = device.create_command_encoder(&Default::default());
    {
        let mut pass = encoder.begin_compute_pass(&Default::default());
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &io_group, &[]);
        pass.set_bind_group(1, &table_group, &[]);
        pass.dispatch_workgroups(gx, gy, 1);
    }
    encoder.copy_buffer_to_buffer(&output, 0, &readback, 0, out_bytes);
    ctx.queue.submit([encoder.finish()]);
    let slice = readback.slice(..);
    let (tx, rx) = std::sync::mpsc::channel();
    slice.map_async(wgpu::MapMode::Read, move |r| {
        let _ = tx.send(r);
    });
    ctx.wait().expect("the GPU finishes");
    rx.recv().unwrap().expect("the results map");
    ctx.check().expect("no device error");
    let data = slice.get_mapped_range().expect("the mapped results");
    let out: &[[f32; 4]] = bytemuck::cast_slice(&data);
    out.iter()
        .map(|o| ([o[0], o[1], o[2]], o[3] as u32))
        .collect()
}

/// The differences found: the largest per unit irradiance, and the largest in units of the
/// steep-edge allowance `1.5 · 2⁻²⁴ / f` per unit irradiance, beyond [`TOLERANCE`].
#[derive(Debug, Default)]
struct Measured {
    max_rel: f32,
    /// The largest per unit irradiance, by way out of the shader (`fringe_branch & 15`).
    by_way: [f32; 16],
    /// On the wide ends integrated exactly (ways 6 and 7, no still factor), the largest
    /// difference of the CPU's and of the GPU's open share from an f64 oracle.
    wide_cpu: f64,
    wide_gpu: f64,
    max_edge: f32,
    failures: Vec<String>,
}

/// Shades `attrs` on the GPU and on the CPU with `aperture` and compares them; the branches
/// taken, counted.
fn compare(
    name: &str,
    tables: &[FringeTable],
    attrs: &[FringeAttrs],
    aperture: &Aperture,
) -> (Measured, [usize; 64]) {
    let cpu_shader = FringeShader {
        tables,
        aperture: aperture.sampler(),
    };
    let gpu = gpu_shade(tables, attrs, aperture);
    let mut m = Measured::default();
    let mut branches = [0_usize; 64];
    for (a, (g, branch)) in attrs.iter().zip(&gpu) {
        branches[*branch as usize % 64] += 1;
        let c = cpu_shader.shade(a);
        let irr = a[0].abs().max(a[1].abs()).max(a[2].abs());
        let edge_unit = 1.5 * f32::EPSILON * 0.5 / a[9];
        if let Some(exact) = wide_oracle(tables, a, *branch) {
            for k in (0..3).filter(|&k| a[k] != 0.0) {
                let share = |v: f32| f64::from(v) / f64::from(a[k]);
                m.wide_cpu = m.wide_cpu.max((share(c[k]) - exact[k]).abs());
                m.wide_gpu = m.wide_gpu.max((share(g[k]) - exact[k]).abs());
            }
        }
        for k in 0..3 {
            let diff = (g[k] - c[k]).abs();
            let rel = diff / irr;
            if rel.is_nan() || rel > m.max_rel {
                m.max_rel = rel;
            }
            let way = &mut m.by_way[*branch as usize & 15];
            *way = way.max(rel);
            let tolerance = if a[10] > 1.5 {
                APERTURE_TOLERANCE
            } else if matches!(branch & 15, 6 | 7) {
                WIDE_TOLERANCE
            } else {
                TOLERANCE
            };
            let edge = (rel - tolerance).max(0.0) / edge_unit;
            if edge.is_nan() || edge > m.max_edge {
                m.max_edge = edge;
            }
            // (NaN fails.)
            let within = diff <= irr * (tolerance + EDGE_TOLERANCE * edge_unit);
            if !within && m.failures.len() < 10 {
                m.failures.push(format!(
                    "{a:?}: channel {k}: GPU {g:?} against CPU {c:?} (branch {branch})"
                ));
            }
        }
    }
    eprintln!(
        "{name}: {} vectors: max |GPU − CPU| / irradiance {:.2e} (by way {}), beyond it {:.2} steep-edge roundings; wide ends against f64: CPU {:.1e}, GPU {:.1e}; branches {:?}",
        attrs.len(),
        m.max_rel,
        m.by_way
            .iter()
            .enumerate()
            .filter(|(_, v)| **v > 0.0)
            .map(|(w, v)| format!("{w}: {v:.1e}"))
            .collect::<Vec<_>>()
            .join(", "),
        m.max_edge,
        m.wide_cpu,
        m.wide_gpu,
        branches
            .iter()
            .enumerate()
            .filter(|(_, n)| **n > 0)
            .collect::<Vec<_>>()
    );
    (m, branches)
}

/// For a vector that took a wide end's exact integral with no still factor (way 6, the clip,
/// or 7, the stop), that integral in f64: `∫₀¹ S(p + q τ) dF` over the table's piecewise
/// linear `F`, each interval split where `p + q τ` crosses 0 and 1.
fn wide_oracle(tables: &[FringeTable], a: &FringeAttrs, branch: u32) -> Option<[f64; 3]> {
    let (x0, x1) = match branch {
        6 => (f64::from(a[3]), f64::from(a[4])),
        7 => {
            let d0 = (a[5] * a[5] + a[7] * a[7]).sqrt();
            let (u, v) = (a[5] + a[6], a[7] + a[8]);
            let d1 = (u * u + v * v).sqrt();
            (f64::from(d0), f64::from(d1 - d0))
        }
        _ => return None,
    };
    let f = f64::from(a[9]);
    let (p, q) = ((1.0 + 0.5 * f - x0) / f, -x1 / f);
    let nodes = tables[a[11] as usize].nodes();
    let n = FringeTable::NODE_COUNT;
    let mut cuts: Vec<f64> = (0..=n).map(|i| i as f64 / n as f64).collect();
    cuts.extend(
        [-p / q, (1.0 - p) / q]
            .into_iter()
            .filter(|t| *t > 0.0 && *t < 1.0),
    );
    cuts.sort_by(f64::total_cmp);
    let mut out = [0.0_f64; 3];
    for w in cuts.windows(2) {
        let (ta, tb) = (w[0], w[1]);
        if tb <= ta {
            continue;
        }
        let i = ((0.5 * (ta + tb) * n as f64) as usize).min(n - 1);
        let (x, y) = ((p + q * ta).clamp(0.0, 1.0), (p + q * tb).clamp(0.0, 1.0));
        let mean_s = (x * x + x * y + y * y) - 0.5 * (x + y) * (x * x + y * y);
        for (c, o) in out.iter_mut().enumerate() {
            let density = f64::from(nodes[i + 1][c] - nodes[i][c]) * n as f64;
            *o += density * (tb - ta) * mean_s;
        }
    }
    Some(out)
}

/// The branch counts by way out (`fringe_branch`'s low four bits).
fn ways(branches: &[usize; 64]) -> [usize; 16] {
    let mut ways = [0_usize; 16];
    for (b, n) in branches.iter().enumerate() {
        ways[b & 15] += n;
    }
    ways
}

/// A small deterministic generator (splitmix64).
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1).
    fn unit(&mut self) -> f32 {
        (self.next() >> 40) as f32 / (1u64 << 24) as f32
    }

    fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.unit()
    }

    fn below(&mut self, n: usize) -> usize {
        (self.next() % n as u64) as usize
    }
}

/// The Heliar's frame (light 8°, 60°, 960 × 540, default quality) meshed with its dispersive
/// ghosts fringed: every mesh's fringed triangles, their tables joined (attribute 11 moved
/// to the joined index).
fn heliar_fringes() -> (Vec<FringeTable>, Vec<[FringeAttrs; 3]>) {
    let sys = load_lens("heliar-tronnier");
    let frame = Frame::across_film(960, 540, sys.film_width_mm);
    let lights = [LightSpec::parse("8,60").unwrap()];
    let opts = PlanOptions::for_quality(Quality::Default, None);
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
    let mut tables = Vec::new();
    let mut triangles = Vec::new();
    for (_, mesh) in &recorded.meshes {
        let base = tables.len() as f32;
        tables.extend(mesh.fringe_tables.iter().cloned());
        for tri in &mesh.fringe.triangles {
            triangles.push(tri.map(|k| {
                let mut a = mesh.fringe.attrs[k as usize];
                a[11] += base;
                a
            }));
        }
    }
    (tables, triangles)
}

/// The attributes at barycentric `(w1, w2)` of a triangle, as a rasterizer's plane gives them
/// (a constant attribute stays exact).
fn at(c: &[FringeAttrs; 3], w1: f32, w2: f32) -> FringeAttrs {
    std::array::from_fn(|k| c[0][k] + w1 * (c[1][k] - c[0][k]) + w2 * (c[2][k] - c[0][k]))
}

/// Points of triangle `c` to shade: its corners and centre, random points inside, and on
/// chords across it (its edges and random segments) points around where the clip radius or
/// the stop's radius crosses 1 at τ = 0, ½ and 1, within a few feathers of it.
fn sample_triangle(c: &[FringeAttrs; 3], rng: &mut Rng, out: &mut Vec<FringeAttrs>) {
    let f = c[0][9];
    out.extend([at(c, 0.0, 0.0), at(c, 1.0, 0.0), at(c, 0.0, 1.0)]);
    out.push(at(c, 1.0 / 3.0, 1.0 / 3.0));
    let random_point = |rng: &mut Rng| {
        let (mut w1, mut w2) = (rng.unit(), rng.unit());
        if w1 + w2 > 1.0 {
            (w1, w2) = (1.0 - w1, 1.0 - w2);
        }
        [w1, w2]
    };
    for _ in 0..4 {
        let [w1, w2] = random_point(rng);
        out.push(at(c, w1, w2));
    }
    let mut chords = vec![
        ([0.0, 0.0], [1.0, 0.0]),
        ([1.0, 0.0], [0.0, 1.0]),
        ([0.0, 1.0], [0.0, 0.0]),
    ];
    for _ in 0..3 {
        chords.push((random_point(rng), random_point(rng)));
    }
    let offsets = [-2.0, -1.0, -0.5, -0.25, 0.0, 0.25, 0.5, 1.0, 2.0];
    for (p, q) in chords {
        let point = |s: f64| {
            let w1 = p[0] as f64 + s * (q[0] - p[0]) as f64;
            let w2 = p[1] as f64 + s * (q[1] - p[1]) as f64;
            (w1, w2)
        };
        for tau in [0.0_f64, 0.5, 1.0] {
            // Along the chord the clip radius at τ is affine, the stop's u and v too.
            let value = |s: f64| -> [f64; 2] {
                let (w1, w2) = point(s);
                let attr = |k: usize| {
                    let v = |i: usize| c[i][k] as f64 + tau * c[i][k + 1] as f64;
                    v(0) + w1 * (v(1) - v(0)) + w2 * (v(2) - v(0))
                };
                [attr(3), attr(5).hypot(attr(7))]
            };
            for which in 0..2 {
                let (g0, g1) = (value(0.0)[which] - 1.0, value(1.0)[which] - 1.0);
                let s_cross = if which == 0 {
                    if g0 == g1 {
                        continue;
                    }
                    g0 / (g0 - g1)
                } else {
                    // The stop's radius is convex along the chord: bisect where it changes
                    // side, else around its nearest approach.
                    let (mut lo, mut hi) = (0.0_f64, 1.0_f64);
                    if (g0 > 0.0) == (g1 > 0.0) {
                        continue;
                    }
                    for _ in 0..60 {
                        let mid = 0.5 * (lo + hi);
                        if (value(mid)[1] - 1.0 > 0.0) == (g0 > 0.0) {
                            lo = mid;
                        } else {
                            hi = mid;
                        }
                    }
                    0.5 * (lo + hi)
                };
                // A feather's width along the chord, from the value's slope there.
                let slope = (value((s_cross + 1e-3).min(1.0))[which]
                    - value((s_cross - 1e-3).max(0.0))[which])
                    .abs()
                    / 2e-3;
                let width = if slope > 0.0 {
                    f64::from(f) / slope
                } else {
                    1.0
                };
                for o in offsets {
                    let jitter = 0.2 * (rng.unit() as f64 - 0.5);
                    let s = (s_cross + (o + jitter) * width).clamp(0.0, 1.0);
                    if s.is_finite() {
                        let (w1, w2) = point(s);
                        out.push(at(c, w1 as f32, w2 as f32));
                    }
                }
            }
        }
    }
}

#[test]
fn the_gpu_shades_the_heliar_s_fringes_as_the_cpu() {
    let (tables, triangles) = heliar_fringes();
    assert!(
        !tables.is_empty() && triangles.len() > 100,
        "the Heliar's frame has fringed ghosts: {} tables, {} triangles",
        tables.len(),
        triangles.len()
    );
    let mut rng = Rng(0x5eed_f1a2);
    let mut attrs = Vec::new();
    for tri in &triangles {
        sample_triangle(tri, &mut rng, &mut attrs);
    }
    let (m, branches) = compare("heliar", &tables, &attrs, &Aperture::Circular);
    assert!(m.failures.is_empty(), "{:#?}", m.failures);
    assert!(
        m.wide_gpu <= WIDE_ORACLE_TOLERANCE,
        "wide ends: {}",
        m.wide_gpu
    );
    // Points on the edges, not only inside.
    let ways = ways(&branches);
    let partial = ways[9] + ways[5] + ways[4] + ways[6] + ways[7];
    assert!(
        partial > attrs.len() / 20,
        "few points on the edges: {branches:?}"
    );
}

/// Five bins of unequal spans and colours (one channel negative in a bin), as the sdk's tests.
fn five_bins() -> FringeTable {
    let spans = [[0.0, 0.3], [0.25, 0.5], [0.5, 0.65], [0.6, 0.8], [0.8, 1.0]];
    let colours = [
        [0.1, 0.2, 1.0],
        [-0.05, 0.5, 0.6],
        [0.3, 1.0, 0.1],
        [0.8, 0.6, 0.0],
        [1.0, 0.1, 0.02],
    ];
    FringeTable::new(&spans, &colours).unwrap()
}

/// A table of `bins` random bins over [0, 1] (narrow ones make steep shares).
fn random_table(rng: &mut Rng, bins: usize) -> FringeTable {
    loop {
        let spans: Vec<[f64; 2]> = (0..bins)
            .map(|b| {
                let centre = (b as f64 + 0.5) / bins as f64;
                let half = 0.5 / bins as f64 * f64::from(rng.range(0.05, 2.0));
                [(centre - half).max(0.0), (centre + half).min(1.0)]
            })
            .collect();
        let colours: Vec<[f64; 3]> = (0..bins)
            .map(|_| std::array::from_fn(|_| f64::from(rng.range(-0.1, 1.0))))
            .collect();
        if let Some(t) = FringeTable::new(&spans, &colours) {
            return t;
        }
    }
}

/// A random valid attribute vector: the clip's and the stop's values near the edge at some
/// τ, their change over τ from nothing to many feathers (wide ramps where it is below about
/// three feathers), the feather from 1e-4 to 0.1, the stop flagged or not.
fn random_attrs(rng: &mut Rng, tables: usize) -> FringeAttrs {
    let f = 10f32.powf(rng.range(-4.0, -1.0));
    // A change over τ of `scale` feathers, either sign; sometimes none at all.
    let change = |rng: &mut Rng| -> f32 {
        match rng.below(8) {
            0 => 0.0,
            1 => 1e-10 * rng.range(-1.0, 1.0),
            2..=4 => f * rng.range(-3.5, 3.5),
            _ => f * 10f32.powf(rng.range(0.0, 3.0)) * if rng.unit() < 0.5 { -1.0 } else { 1.0 },
        }
    };
    // A value crossing 1 (within a few feathers) at a random τ, or anywhere near it.
    let near_edge = |rng: &mut Rng, slope: f32| -> f32 {
        if rng.below(4) == 0 {
            rng.range(0.5, 1.3)
        } else {
            1.0 + f * rng.range(-3.0, 3.0) - slope * rng.range(-0.2, 1.2)
        }
    };
    let r1 = change(rng);
    let r0 = near_edge(rng, r1);
    // The stop: its crossing at τ = 0 at a radius near 1 in a random direction, moving
    // anywhere (along, across, or grazing the edge).
    let phi = rng.range(0.0, std::f32::consts::TAU);
    let d1 = change(rng);
    let radius = near_edge(rng, d1);
    let (u0, v0) = (radius * phi.cos(), radius * phi.sin());
    let (u1, v1) = match rng.below(4) {
        // Radially: the radius nearly linear in τ.
        0 => (d1 * phi.cos(), d1 * phi.sin()),
        // Tangentially: grazing.
        1 => (-d1 * phi.sin(), d1 * phi.cos()),
        2 => (0.0, 0.0),
        _ => {
            let psi = rng.range(0.0, std::f32::consts::TAU);
            (d1 * psi.cos(), d1 * psi.sin())
        }
    };
    let flag = if rng.below(3) == 0 { 0.0 } else { 1.0 };
    let rgb: [f32; 3] = std::array::from_fn(|_| 10f32.powf(rng.range(-2.0, 2.0)));
    [
        rgb[0],
        rgb[1],
        rgb[2],
        r0,
        r1,
        u0,
        u1,
        v0,
        v1,
        f,
        flag,
        rng.below(tables) as f32,
    ]
}

#[test]
fn the_gpu_shades_random_fringes_as_the_cpu() {
    let mut rng = Rng(0xf1a2_ebea);
    let mut tables = vec![
        five_bins(),
        FringeTable::new(&[[0.0, 1.0]], &[[1.0; 3]]).unwrap(),
    ];
    for bins in [3, 8, 40] {
        tables.push(random_table(&mut rng, bins));
    }
    let attrs: Vec<FringeAttrs> = (0..200_000)
        .map(|_| random_attrs(&mut rng, tables.len()))
        .collect();
    let (m, branches) = compare("random", &tables, &attrs, &Aperture::Circular);
    assert!(m.failures.is_empty(), "{:#?}", m.failures);
    assert!(
        m.wide_gpu <= WIDE_ORACLE_TOLERANCE,
        "wide ends: {}",
        m.wide_gpu
    );
    // Every branch taken, often: the low four bits are the way out, 16 and 32 the still
    // clip and stop.
    let ways = ways(&branches);
    let (mut still_clip, mut still_stop) = (0, 0);
    for (b, n) in branches.iter().enumerate() {
        if b & 16 != 0 {
            still_clip += n;
        }
        if b & 32 != 0 {
            still_stop += n;
        }
    }
    for (way, n) in ways.iter().enumerate().take(12).skip(1) {
        assert!(*n >= 100, "branch {way} taken {n} times: {branches:?}");
    }
    assert!(still_clip >= 100 && still_stop >= 100, "{branches:?}");
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

/// Vectors flagged for an iris or a mask (`APERTURE_FLAG`): the random ones, flagged, and the
/// GPU's stepped transmission (`aperture_soft` at each step of τ), its outline shaded as the
/// clip's edge or as a linear transmission where the clip is open (the aperture at three
/// points), and its decisions
/// where the whole segment is open or closed (`aperture_uniform_around`) against the CPU's.
#[test]
fn the_gpu_shades_iris_and_mask_fringes_as_the_cpu() {
    let mut rng = Rng(0x1415_f1a2);
    let mut tables = vec![five_bins()];
    for bins in [3, 8] {
        tables.push(random_table(&mut rng, bins));
    }
    let iris = Aperture::Iris {
        blades: 6,
        rotation_rad: 0.3,
        roundness: 0.2,
    };
    for (name, aperture) in [("iris", iris), ("mask", olf_mask())] {
        let attrs: Vec<FringeAttrs> = (0..50_000)
            .map(|_| {
                let mut a = random_attrs(&mut rng, tables.len());
                a[10] = APERTURE_FLAG;
                a
            })
            .collect();
        let (m, branches) = compare(name, &tables, &attrs, &aperture);
        assert!(m.failures.is_empty(), "{name}: {:#?}", m.failures);
        let ways = ways(&branches);
        // Stepped (13), the outline shaded as the clip's edge (14) or as a linear
        // transmission (15), closed along the segment (12), and open: the clip's own ways.
        assert!(
            ways[13] >= 1000
                && ways[14] >= 300
                && ways[15] >= 100
                && ways[12] >= 100
                && ways[9] + ways[11] >= 100,
            "{name}: {branches:?}"
        );
    }
}
