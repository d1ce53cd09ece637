//! Spectral reference lines (nm) used for dispersion and paraxial analysis.

/// Helium d line, the reference wavelength for nd and the default analysis wavelength.
pub const LAMBDA_D_NM: f64 = 587.5618;
/// Hydrogen F line.
pub const LAMBDA_F_NM: f64 = 486.1327;
/// Hydrogen C line.
pub const LAMBDA_C_NM: f64 = 656.2725;
