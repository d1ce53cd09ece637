//! What became of a ray.

/// The first thing that happened to a ray that stops it reaching the sensor, or `Sensor`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Fate {
    /// Reached the sensor inside every clear aperture.
    Sensor,
    /// Passed outside the clear semi-diameter of `surface` (tracing goes on, so the ray still
    /// says where it would have landed).
    Vignetted { surface: usize },
    /// Total internal reflection at `surface` (tracing stops).
    TotalInternalReflection { surface: usize },
    /// The ray's line does not meet `surface` (tracing stops).
    Missed { surface: usize },
    /// The asphere intersection at `surface` did not converge (tracing stops).
    NoConvergence { surface: usize },
}

impl Fate {
    /// True when the ray reached the sensor unobstructed.
    pub fn reached_sensor(self) -> bool {
        self == Fate::Sensor
    }

    /// A short machine-readable name (`sensor`, `vignetted`, `tir`, `missed`, `no_convergence`).
    pub fn kind(self) -> &'static str {
        match self {
            Fate::Sensor => "sensor",
            Fate::Vignetted { .. } => "vignetted",
            Fate::TotalInternalReflection { .. } => "tir",
            Fate::Missed { .. } => "missed",
            Fate::NoConvergence { .. } => "no_convergence",
        }
    }

    /// The surface where it happened, if any.
    pub fn surface(self) -> Option<usize> {
        match self {
            Fate::Sensor => None,
            Fate::Vignetted { surface }
            | Fate::TotalInternalReflection { surface }
            | Fate::Missed { surface }
            | Fate::NoConvergence { surface } => Some(surface),
        }
    }

    /// Whether tracing stopped here (everything but vignetting and the sensor).
    pub fn is_terminal(self) -> bool {
        !matches!(self, Fate::Sensor | Fate::Vignetted { .. })
    }

    pub(crate) fn encode(self) -> u32 {
        let (kind, s) = match self {
            Fate::Sensor => return 0,
            Fate::Vignetted { surface } => (1, surface),
            Fate::Missed { surface } => (2, surface),
            Fate::TotalInternalReflection { surface } => (3, surface),
            Fate::NoConvergence { surface } => (4, surface),
        };
        (kind << 24) | (s as u32 & 0x00ff_ffff)
    }

    pub(crate) fn decode(code: u32) -> Fate {
        let surface = (code & 0x00ff_ffff) as usize;
        match (code >> 24) & 0x7f {
            1 => Fate::Vignetted { surface },
            2 => Fate::Missed { surface },
            3 => Fate::TotalInternalReflection { surface },
            4 => Fate::NoConvergence { surface },
            _ => Fate::Sensor,
        }
    }
}

impl std::fmt::Display for Fate {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Fate::Sensor => write!(f, "reached the sensor"),
            Fate::Vignetted { surface } => write!(f, "vignetted at surface {surface}"),
            Fate::TotalInternalReflection { surface } => {
                write!(f, "total internal reflection at surface {surface}")
            }
            Fate::Missed { surface } => write!(f, "missed surface {surface}"),
            Fate::NoConvergence { surface } => {
                write!(
                    f,
                    "asphere intersection did not converge at surface {surface}"
                )
            }
        }
    }
}
