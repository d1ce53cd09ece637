//! The layout of every ABI v1 type (size, alignment, field offsets) as text, for the snapshot
//! test that makes an accidental ABI change fail (`sdk/tests/abi_layout.rs`).

use std::fmt::Write;
use std::mem::{align_of, offset_of, size_of};

use super::*;

macro_rules! describe {
    ($out:ident, $ty:ty { $($field:ident),* $(,)? }) => {{
        let _ = writeln!(
            $out,
            "{} size {} align {}",
            stringify!($ty),
            size_of::<$ty>(),
            align_of::<$ty>()
        );
        $(
            let _ = writeln!($out, "  {:>3} {}", offset_of!($ty, $field), stringify!($field));
        )*
    }};
}

/// One block per type: `Name size S align A`, then `offset field` lines, in declaration order.
pub fn describe() -> String {
    let mut out = String::new();
    let _ = writeln!(
        out,
        "ABI {ABI_MAJOR}.{ABI_MINOR}, magic {:?}, entry {ENTRY_SYMBOL}",
        std::str::from_utf8(&MAGIC).unwrap_or("?")
    );
    describe!(out, AbiStr { ptr, len });
    describe!(
        out,
        PluginHeader {
            magic,
            abi_major,
            abi_minor,
            struct_size,
            panic_unwind,
            reserved,
            sdk_version,
            rustc_version,
            name,
            version,
            description,
            kind,
            param_count,
            params,
            create,
            destroy,
            prepare,
            render,
        }
    );
    describe!(
        out,
        ParamDesc {
            name,
            help,
            kind,
            reserved,
            min,
            max,
            default,
            choices
        }
    );
    describe!(out, ErrorBuf { ptr, capacity, len });
    describe!(out, LensInput { xml });
    describe!(
        out,
        LightInput {
            theta_deg,
            phi_deg,
            intensity,
            kelvin
        }
    );
    describe!(out, LightExt { spectrum, rgb });
    describe!(
        out,
        ApertureInput {
            kind,
            blades,
            rotation_rad,
            roundness
        }
    );
    describe!(
        out,
        SceneInput {
            struct_size,
            light_count,
            lights,
            width,
            height,
            film_width_mm,
            film_height_mm,
            aperture,
            mask_width,
            mask_height,
            mask,
            light_ext
        }
    );
    describe!(
        out,
        ImageBuffer {
            pixels,
            width,
            height
        }
    );
    describe!(out, MeshVertex { x, y, rgb });
    describe!(
        out,
        MeshBuffer {
            vertices,
            vertex_capacity,
            vertex_count,
            triangles,
            triangle_capacity,
            triangle_count
        }
    );
    describe!(
        out,
        RenderOutput {
            image,
            mesh,
            items_drawn,
            reserved
        }
    );
    out
}
