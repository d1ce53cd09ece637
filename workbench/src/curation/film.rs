//! The film formats a curated lens is given, from its system as its name says: FlareSim gave
//! every lens a 36 × 24 mm film, wrong for APS-C, Four Thirds and medium-format lenses.

use std::fmt;

/// A camera system's film (sensor) size.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Film {
    /// 35 mm full frame, 36 × 24 mm: FlareSim's for every lens, kept where the name names no
    /// other system.
    FullFrame,
    /// APS-C, 23.5 × 15.6 mm: Nikon DX, Sony E/DT, Fujifilm X, Pentax DA, Samsung NX, Sigma DC,
    /// Leica TL, Ricoh GR.
    ApsC,
    /// Canon's APS-C, 22.3 × 14.9 mm: EF-S, EF-M, RF-S.
    ApsCCanon,
    /// Four Thirds and Micro Four Thirds, 17.3 × 13 mm: Olympus Zuiko Digital and M.Zuiko,
    /// Panasonic Lumix G, Leica DG.
    FourThirds,
    /// Digital medium format, 43.8 × 32.9 mm: Fujifilm GF, Hasselblad XCD, Pentax D FA645.
    Medium44x33,
    /// 645 film, 56 × 41.5 mm: Hasselblad HC, Pentax 645, Mamiya 645.
    Medium645,
    /// 6 × 6 film, 56 × 56 mm: Hasselblad V (C, CF, CFE).
    Medium6x6,
    /// 6 × 7 film, 69.5 × 56 mm: Pentax 6×7, Mamiya RB/RZ67.
    Medium6x7,
}

impl Film {
    pub const ALL: [Film; 8] = [
        Film::FullFrame,
        Film::ApsC,
        Film::ApsCCanon,
        Film::FourThirds,
        Film::Medium44x33,
        Film::Medium645,
        Film::Medium6x6,
        Film::Medium6x7,
    ];

    /// The code used in the selection list.
    pub fn code(self) -> &'static str {
        match self {
            Film::FullFrame => "ff",
            Film::ApsC => "aps-c",
            Film::ApsCCanon => "aps-c-canon",
            Film::FourThirds => "mft",
            Film::Medium44x33 => "44x33",
            Film::Medium645 => "645",
            Film::Medium6x6 => "6x6",
            Film::Medium6x7 => "6x7",
        }
    }

    pub fn parse(code: &str) -> Option<Film> {
        Film::ALL.into_iter().find(|f| f.code() == code)
    }

    /// Width and height (mm).
    pub fn size_mm(self) -> (f64, f64) {
        match self {
            Film::FullFrame => (36.0, 24.0),
            Film::ApsC => (23.5, 15.6),
            Film::ApsCCanon => (22.3, 14.9),
            Film::FourThirds => (17.3, 13.0),
            Film::Medium44x33 => (43.8, 32.9),
            Film::Medium645 => (56.0, 41.5),
            Film::Medium6x6 => (56.0, 56.0),
            Film::Medium6x7 => (69.5, 56.0),
        }
    }

    /// The system's name, for notes.
    pub fn system(self) -> &'static str {
        match self {
            Film::FullFrame => "35 mm full frame",
            Film::ApsC => "APS-C",
            Film::ApsCCanon => "Canon APS-C",
            Film::FourThirds => "Four Thirds",
            Film::Medium44x33 => "digital medium format (44 × 33)",
            Film::Medium645 => "645 medium format",
            Film::Medium6x6 => "6 × 6 medium format",
            Film::Medium6x7 => "6 × 7 medium format",
        }
    }
}

impl fmt::Display for Film {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let (w, h) = self.size_mm();
        write!(f, "{w} × {h} mm ({})", self.system())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_film_reads_back_from_its_code_and_is_landscape() {
        for film in Film::ALL {
            assert_eq!(Film::parse(film.code()), Some(film));
            let (w, h) = film.size_mm();
            assert!(w >= h && h > 0.0, "{film}");
        }
        assert_eq!(Film::parse("FF"), None);
    }
}
