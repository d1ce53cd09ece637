//! The render pipelines and their bind group layouts: one raster pipeline per kind of ghost
//! triangle (wholly open, edge, fringed), and the upsampling pass; the constructors of the
//! full-frame pipelines the compositor draws with too (`pipeline`, `additive_target`).

use crate::targets::AccumFormat;

/// The kinds of ghost triangle (flarebench_sdk::ghost::mesh::GhostMesh's three meshes).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    Open = 0,
    Edge = 1,
    Fringe = 2,
}

impl Kind {
    /// Floats per corner.
    pub fn attrs(self) -> u32 {
        match self {
            Kind::Open => 3,
            Kind::Edge => 8,
            Kind::Fringe => 12,
        }
    }

    pub fn label(self) -> &'static str {
        match self {
            Kind::Open => "open triangles",
            Kind::Edge => "edge triangles",
            Kind::Fringe => "fringed triangles",
        }
    }

    fn entry(self) -> &'static str {
        match self {
            Kind::Open => "fs_open",
            Kind::Edge => "fs_edge",
            Kind::Fringe => "fs_fringe",
        }
    }
}

/// The raster shaders: the aperture and the rasterizer (with the open and edge shades).
const RASTER_WGSL: &str = concat!(
    include_str!("shaders/aperture.wgsl"),
    include_str!("shaders/raster.wgsl")
);

/// The fringe pipeline's module: the raster shaders, the fringe shade and its entry point.
const FRINGE_WGSL: &str = concat!(
    include_str!("shaders/aperture.wgsl"),
    include_str!("shaders/raster.wgsl"),
    include_str!("shaders/fringe.wgsl"),
    include_str!("shaders/fringe_entry.wgsl")
);

/// Every pipeline the ghost renderer uses.
#[derive(Debug)]
pub struct Pipelines {
    raster_layout: wgpu::BindGroupLayout,
    fringe_layout: wgpu::BindGroupLayout,
    upsample_layout: wgpu::BindGroupLayout,
    raster: [wgpu::RenderPipeline; 3],
    pub upsample: wgpu::RenderPipeline,
}

fn storage_entry(binding: u32, visibility: wgpu::ShaderStages) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Storage { read_only: true },
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}

fn uniform_entry(
    binding: u32,
    visibility: wgpu::ShaderStages,
    dynamic: bool,
    size: u64,
) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Uniform,
            has_dynamic_offset: dynamic,
            min_binding_size: wgpu::BufferSize::new(size),
        },
        count: None,
    }
}

/// Additive blending of colour; alpha is kept at 0.
const ADD: wgpu::BlendState = wgpu::BlendState {
    color: wgpu::BlendComponent {
        src_factor: wgpu::BlendFactor::One,
        dst_factor: wgpu::BlendFactor::One,
        operation: wgpu::BlendOperation::Add,
    },
    alpha: wgpu::BlendComponent {
        src_factor: wgpu::BlendFactor::One,
        dst_factor: wgpu::BlendFactor::One,
        operation: wgpu::BlendOperation::Add,
    },
};

/// A linear target of `format` blended additively.
pub(crate) fn additive_target(format: AccumFormat) -> wgpu::ColorTargetState {
    wgpu::ColorTargetState {
        format: format.texture_format(),
        blend: Some(ADD),
        write_mask: wgpu::ColorWrites::ALL,
    }
}

/// A render pipeline of one module's vertex and fragment entries (`entries`), one bind group
/// (`layout`) and one colour target, drawing whole triangles without vertex buffers.
pub(crate) fn pipeline(
    device: &wgpu::Device,
    layout: &wgpu::BindGroupLayout,
    source: &str,
    entries: (&str, &str),
    target: wgpu::ColorTargetState,
) -> wgpu::RenderPipeline {
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some(entries.1),
        source: wgpu::ShaderSource::Wgsl(source.into()),
    });
    let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some(entries.1),
        bind_group_layouts: &[Some(layout)],
        immediate_size: 0,
    });
    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some(entries.1),
        layout: Some(&pipeline_layout),
        vertex: wgpu::VertexState {
            module: &module,
            entry_point: Some(entries.0),
            compilation_options: Default::default(),
            buffers: &[],
        },
        primitive: wgpu::PrimitiveState::default(),
        depth_stencil: None,
        multisample: wgpu::MultisampleState::default(),
        fragment: Some(wgpu::FragmentState {
            module: &module,
            entry_point: Some(entries.1),
            compilation_options: Default::default(),
            targets: &[Some(target)],
        }),
        multiview_mask: None,
        cache: None,
    })
}

impl Pipelines {
    /// The pipelines drawing into targets of `format`.
    pub fn new(device: &wgpu::Device, format: AccumFormat) -> Pipelines {
        use wgpu::ShaderStages as S;
        let both = S::VERTEX | S::FRAGMENT;
        let raster_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("raster"),
            entries: &[
                uniform_entry(0, both, true, 16),
                storage_entry(1, both),
                storage_entry(2, both),
                storage_entry(3, both),
                uniform_entry(4, S::FRAGMENT, false, 80),
                storage_entry(5, S::FRAGMENT),
            ],
        });
        let fringe_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("fringe tables"),
            entries: &[storage_entry(0, S::FRAGMENT)],
        });
        let upsample_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("upsample"),
            entries: &[
                uniform_entry(0, S::FRAGMENT, true, 16),
                wgpu::BindGroupLayoutEntry {
                    binding: 1,
                    visibility: S::FRAGMENT,
                    ty: wgpu::BindingType::Texture {
                        sample_type: wgpu::TextureSampleType::Float { filterable: false },
                        view_dimension: wgpu::TextureViewDimension::D2,
                        multisampled: false,
                    },
                    count: None,
                },
            ],
        });
        let raster_module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("raster"),
            source: wgpu::ShaderSource::Wgsl(RASTER_WGSL.into()),
        });
        let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("raster"),
            bind_group_layouts: &[Some(&raster_layout)],
            immediate_size: 0,
        });
        let fringe_module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("fringe"),
            source: wgpu::ShaderSource::Wgsl(FRINGE_WGSL.into()),
        });
        let fringe_pipeline_layout =
            device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some("fringe"),
                bind_group_layouts: &[Some(&raster_layout), Some(&fringe_layout)],
                immediate_size: 0,
            });
        let raster = [
            raster_pipeline(device, &layout, &raster_module, Kind::Open, format),
            raster_pipeline(device, &layout, &raster_module, Kind::Edge, format),
            raster_pipeline(
                device,
                &fringe_pipeline_layout,
                &fringe_module,
                Kind::Fringe,
                format,
            ),
        ];
        let upsample = pipeline(
            device,
            &upsample_layout,
            include_str!("shaders/upsample.wgsl"),
            ("vs_full", "fs_upsample"),
            additive_target(format),
        );
        Pipelines {
            raster_layout,
            fringe_layout,
            upsample_layout,
            raster,
            upsample,
        }
    }

    /// The raster pipeline of `kind`.
    pub fn raster(&self, kind: Kind) -> &wgpu::RenderPipeline {
        &self.raster[kind as usize]
    }

    /// The raster bind group: level blocks, positions, attributes, triangles, aperture block,
    /// mask fields.
    pub fn raster_bind_group(
        &self,
        device: &wgpu::Device,
        b: [&wgpu::Buffer; 6],
    ) -> wgpu::BindGroup {
        device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("raster"),
            layout: &self.raster_layout,
            entries: &[
                entry(0, b[0], Some(16)),
                entry(1, b[1], None),
                entry(2, b[2], None),
                entry(3, b[3], None),
                entry(4, b[4], None),
                entry(5, b[5], None),
            ],
        })
    }

    /// The fringe tables' bind group.
    pub fn fringe_bind_group(
        &self,
        device: &wgpu::Device,
        tables: &wgpu::Buffer,
    ) -> wgpu::BindGroup {
        device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("fringe tables"),
            layout: &self.fringe_layout,
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: tables.as_entire_binding(),
            }],
        })
    }

    /// The upsampling bind group of one coarse level.
    pub fn upsample_bind_group(
        &self,
        device: &wgpu::Device,
        blocks: &wgpu::Buffer,
        view: &wgpu::TextureView,
    ) -> wgpu::BindGroup {
        device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("upsample"),
            layout: &self.upsample_layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                        buffer: blocks,
                        offset: 0,
                        size: wgpu::BufferSize::new(16),
                    }),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: wgpu::BindingResource::TextureView(view),
                },
            ],
        })
    }
}

fn entry(binding: u32, buffer: &wgpu::Buffer, size: Option<u64>) -> wgpu::BindGroupEntry<'_> {
    wgpu::BindGroupEntry {
        binding,
        resource: wgpu::BindingResource::Buffer(wgpu::BufferBinding {
            buffer,
            offset: 0,
            size: size.and_then(wgpu::BufferSize::new),
        }),
    }
}

fn raster_pipeline(
    device: &wgpu::Device,
    layout: &wgpu::PipelineLayout,
    module: &wgpu::ShaderModule,
    kind: Kind,
    format: AccumFormat,
) -> wgpu::RenderPipeline {
    let constants = [("ATTRS", f64::from(kind.attrs()))];
    let options = wgpu::PipelineCompilationOptions {
        constants: &constants,
        zero_initialize_workgroup_memory: false,
    };
    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some(kind.label()),
        layout: Some(layout),
        vertex: wgpu::VertexState {
            module,
            entry_point: Some("vs_main"),
            compilation_options: options.clone(),
            buffers: &[],
        },
        primitive: wgpu::PrimitiveState {
            topology: wgpu::PrimitiveTopology::TriangleList,
            cull_mode: None,
            ..Default::default()
        },
        depth_stencil: None,
        multisample: wgpu::MultisampleState::default(),
        fragment: Some(wgpu::FragmentState {
            module,
            entry_point: Some(kind.entry()),
            compilation_options: options,
            targets: &[Some(additive_target(format))],
        }),
        multiview_mask: None,
        cache: None,
    })
}

#[cfg(test)]
mod tests {
    /// The WGSL rasterizer samples the same triangles as the CPU's (`Coverage::Sampled`).
    #[test]
    fn the_shader_s_narrowest_sampled_triangle_is_the_cpu_s() {
        let want = format!(
            "const MIN_SAMPLED_WIDTH: f32 = {:?};",
            flarebench_sdk::raster::MIN_SAMPLED_WIDTH as f32
        );
        assert!(
            super::RASTER_WGSL.contains(&want),
            "raster.wgsl lacks `{want}`"
        );
    }
}
