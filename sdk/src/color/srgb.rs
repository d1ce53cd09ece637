//! Linear sRGB (IEC 61966-2-1:1999): the XYZ → RGB matrix for the D65 white point, its inverse,
//! luminance, and the sRGB transfer function used for 8-bit output.

/// XYZ → linear sRGB, the matrix printed in IEC 61966-2-1 (primaries R (0.64, 0.33),
/// G (0.30, 0.60), B (0.15, 0.06), white D65 (0.3127, 0.3290)), rows R, G, B.
/// D65 (X, Y, Z) = (0.9505, 1, 1.0891) maps to (1, 1, 1) within 2e-4.
pub const XYZ_TO_LINEAR_SRGB: [[f64; 3]; 3] = [
    [3.2406, -1.5372, -0.4986],
    [-0.9689, 1.8758, 0.0415],
    [0.0557, -0.2040, 1.0570],
];

/// Linear sRGB → XYZ, the inverse printed in IEC 61966-2-1; rows X, Y, Z. The middle row is
/// the luminance weights of [`luminance`].
pub const LINEAR_SRGB_TO_XYZ: [[f64; 3]; 3] = [
    [0.4124, 0.3576, 0.1805],
    [0.2126, 0.7152, 0.0722],
    [0.0193, 0.1192, 0.9505],
];

/// Luminance weights of linear sRGB: `Y = 0.2126 R + 0.7152 G + 0.0722 B`.
pub const LUMINANCE_WEIGHTS: [f64; 3] = [0.2126, 0.7152, 0.0722];

/// Linear sRGB of the tristimulus values `xyz` (no clamping: colours outside the sRGB gamut
/// have a negative component).
pub fn xyz_to_linear_srgb(xyz: [f64; 3]) -> [f64; 3] {
    mul(&XYZ_TO_LINEAR_SRGB, xyz)
}

/// XYZ of the linear sRGB colour `rgb`.
pub fn linear_srgb_to_xyz(rgb: [f64; 3]) -> [f64; 3] {
    mul(&LINEAR_SRGB_TO_XYZ, rgb)
}

/// Luminance `Y` of a linear sRGB colour.
pub fn luminance(rgb: [f64; 3]) -> f64 {
    LUMINANCE_WEIGHTS[0] * rgb[0] + LUMINANCE_WEIGHTS[1] * rgb[1] + LUMINANCE_WEIGHTS[2] * rgb[2]
}

/// Luminance `Y` of a linear sRGB pixel (f32).
pub fn luminance_f32(rgb: [f32; 3]) -> f32 {
    0.2126 * rgb[0] + 0.7152 * rgb[1] + 0.0722 * rgb[2]
}

/// The sRGB transfer function (IEC 61966-2-1), linear → encoded, on [0, 1]:
/// `12.92 v` for `v ≤ 0.0031308`, else `1.055 v^(1/2.4) − 0.055`. Input is clamped to [0, 1]
/// first (NaN gives 0).
pub fn encode(linear: f32) -> f32 {
    let v = if linear >= 0.0 { linear.min(1.0) } else { 0.0 };
    if v <= 0.003_130_8 {
        12.92 * v
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    }
}

/// The inverse of [`encode`], encoded → linear, on [0, 1]: `v / 12.92` for `v ≤ 0.04045`, else
/// `((v + 0.055) / 1.055)^2.4`. Input is clamped to [0, 1] first (NaN gives 0).
pub fn decode(encoded: f32) -> f32 {
    let v = if encoded >= 0.0 {
        encoded.min(1.0)
    } else {
        0.0
    };
    if v <= 0.040_45 {
        v / 12.92
    } else {
        ((v + 0.055) / 1.055).powf(2.4)
    }
}

fn mul(m: &[[f64; 3]; 3], v: [f64; 3]) -> [f64; 3] {
    std::array::from_fn(|r| m[r][0] * v[0] + m[r][1] * v[1] + m[r][2] * v[2])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_d65_white_point_maps_to_rgb_one() {
        // D65 chromaticity (0.3127, 0.3290) at Y = 1.
        let (x, y) = (0.3127, 0.3290);
        let rgb = xyz_to_linear_srgb([x / y, 1.0, (1.0 - x - y) / y]);
        for c in rgb {
            assert!((c - 1.0).abs() < 2e-4, "{rgb:?}");
        }
    }

    /// The two printed matrices are inverse to their four decimals.
    #[test]
    fn the_printed_matrices_are_inverse_to_their_precision() {
        for (i, e) in [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]
            .into_iter()
            .enumerate()
        {
            let back = xyz_to_linear_srgb(linear_srgb_to_xyz(e));
            for c in 0..3 {
                let want = if c == i { 1.0 } else { 0.0 };
                assert!((back[c] - want).abs() < 5e-4, "{i}: {back:?}");
            }
        }
    }

    #[test]
    fn luminance_of_white_is_one() {
        assert!((luminance([1.0; 3]) - 1.0).abs() < 1e-12);
        assert!((luminance_f32([1.0; 3]) - 1.0).abs() < 1e-6);
    }

    #[test]
    fn the_transfer_function_has_the_standard_values() {
        assert_eq!(encode(0.0), 0.0);
        assert!((encode(1.0) - 1.0).abs() < 1e-6);
        // Linear segment: 0.002 × 12.92.
        assert!((encode(0.002) - 0.025_84).abs() < 1e-7);
        // 18% grey encodes to 0.4613561 (1.055 × 0.18^(1/2.4) − 0.055).
        assert!((encode(0.18) - 0.461_356_1).abs() < 1e-6);
        // Both segments meet at the threshold (to the standard's rounding, 3e-5).
        let lo = 12.92 * 0.003_130_8_f32;
        let hi = 1.055 * 0.003_130_8_f32.powf(1.0 / 2.4) - 0.055;
        assert!((lo - hi).abs() < 3e-5);
        assert_eq!(encode(-1.0), 0.0);
        assert_eq!(encode(f32::NAN), 0.0);
        assert!((encode(7.0) - 1.0).abs() < 1e-6);
    }

    #[test]
    fn decode_inverts_encode() {
        for i in 0..=1000 {
            let v = i as f32 / 1000.0;
            assert!((decode(encode(v)) - v).abs() < 2e-6, "{v}");
        }
    }
}
