//! The exact motion of the `spring` scene, derived here independently of the
//! simulator: a mass `m` hanging below a fixed point on a spring of stiffness `k`,
//! damping `b` and rest length `L`, under gravity `g`.
//!
//! With `l` the spring's length (the mass moves on the vertical line only),
//! `m l'' = -k (l - L) - b l' + m g`. Around the equilibrium `l_eq = L + m g / k`,
//! `u = l - l_eq` obeys `u'' + 2 zeta omega0 u' + omega0² u = 0` with
//! `omega0 = sqrt(k/m)` and `zeta = b / (2 sqrt(k m))`, whose solution for `u(0) = u0`,
//! `u'(0) = v0` is, underdamped (`zeta < 1`, `omega_d = omega0 sqrt(1 - zeta²)`):
//! `u = e^(-zeta omega0 t) [u0 cos(omega_d t) + (v0 + zeta omega0 u0)/omega_d sin(omega_d t)]`;
//! critically damped: `u = e^(-omega0 t) [u0 + (v0 + omega0 u0) t]`; overdamped
//! (`r± = -omega0 (zeta ∓ sqrt(zeta² - 1))`): `u = c+ e^(r+ t) + c- e^(r- t)`.

/// A damped harmonic oscillator `u'' + 2 zeta omega0 u' + omega0² u = 0`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DampedOscillator {
    /// Undamped angular frequency in rad/s.
    pub omega0: f64,
    /// Damping ratio.
    pub zeta: f64,
    /// Initial displacement.
    pub u0: f64,
    /// Initial velocity.
    pub v0: f64,
}

impl DampedOscillator {
    /// Displacement at time `t`.
    pub fn displacement(&self, t: f64) -> f64 {
        let (w, z, u0, v0) = (self.omega0, self.zeta, self.u0, self.v0);
        if z < 1.0 {
            let wd = w * (1.0 - z * z).sqrt();
            (-z * w * t).exp() * (u0 * (wd * t).cos() + (v0 + z * w * u0) / wd * (wd * t).sin())
        } else if z == 1.0 {
            (-w * t).exp() * (u0 + (v0 + w * u0) * t)
        } else {
            let s = (z * z - 1.0).sqrt();
            let (rp, rm) = (-w * (z - s), -w * (z + s));
            // u0 = cp + cm, v0 = rp cp + rm cm.
            let cp = (v0 - rm * u0) / (rp - rm);
            let cm = u0 - cp;
            cp * (rp * t).exp() + cm * (rm * t).exp()
        }
    }
}

/// The hanging spring: parameters in SI units, the fixed end at height `anchor_y`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HangingSpring {
    /// Height of the fixed end in m.
    pub anchor_y: f64,
    /// Rest length `L` in m.
    pub rest: f64,
    /// Stiffness in N/m.
    pub stiffness: f64,
    /// Damping in N·s/m.
    pub damping: f64,
    /// Mass of the hanging particle in kg.
    pub mass: f64,
    /// Gravitational acceleration pulling down, m/s² (positive).
    pub gravity: f64,
    /// Initial length `l(0)` in m (the mass starts at rest).
    pub initial_length: f64,
}

impl HangingSpring {
    /// The oscillation about the equilibrium.
    pub fn oscillator(&self) -> DampedOscillator {
        let omega0 = (self.stiffness / self.mass).sqrt();
        DampedOscillator {
            omega0,
            zeta: self.damping / (2.0 * (self.stiffness * self.mass).sqrt()),
            u0: self.initial_length - self.equilibrium_length(),
            v0: 0.0,
        }
    }

    /// `l_eq = L + m g / k`.
    pub fn equilibrium_length(&self) -> f64 {
        self.rest + self.mass * self.gravity / self.stiffness
    }

    /// Height of the mass at time `t`, in m.
    pub fn height(&self, t: f64) -> f64 {
        self.anchor_y - (self.equilibrium_length() + self.oscillator().displacement(t))
    }
}
