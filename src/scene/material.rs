//! Cloth materials: named sets of a fabric's properties (`material = "cotton"`)
//! that hold whatever the spacing, so a cloth refined to more particles over the
//! same size is the same cloth.
//!
//! On a square spring grid a spring of stiffness `k` across spacing `L` carries a
//! stress (force per width) `k ε L / L = k ε` at strain `ε`, so `k` in N/m is the
//! sheet's stretch modulus at every spacing; damping `b` likewise. The mass per
//! particle is the mass per area times the cloth's area over its particles, so
//! wave speeds `L sqrt(k / m) = sqrt(k / ρ_A)` and the sag under its own weight,
//! strain `ρ_A g y / k`, do not depend on the spacing. Bend springs resist a small
//! curvature only at fourth order (their length changes with its square), so no
//! spacing rule makes them a bending modulus; a material gives them a fixed
//! multiple of `k`, as scene files do.

use super::SceneSpec;

/// A fabric's properties, each the value of a scene key.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Material {
    /// The name in scene files (`material = "..."`) and the panel.
    pub name: &'static str,
    /// Mass per area in kg/m² (`areal_density`).
    pub areal_density: f64,
    /// Stretch stiffness k in N/m (`stiffness`), the same at every spacing.
    pub stiffness: f64,
    /// Spring damping b in N·s/m (`damping`).
    pub damping: f64,
    /// Shear springs' stiffness as a multiple of k (`shear_scale`, grids).
    pub shear_scale: f64,
    /// Bend springs' stiffness as a multiple of k (`bend_scale`).
    pub bend_scale: f64,
    /// Aerodynamic drag coefficient (`drag_coefficient`).
    pub drag_coefficient: f64,
    /// What it is like, for the panel's tip.
    pub about: &'static str,
}

/// The built-in materials, lightest first. Masses per area are those of the real
/// fabrics (silk habotai about 50 g/m², denim 400 g/m², 1 mm rubber 1.2 kg/m²);
/// stiffnesses are far below real fabrics' (1e4 to 1e5 N/m) so that a frame
/// needs tens of steps, not thousands, and keep their order.
pub const MATERIALS: [Material; 5] = [
    Material {
        name: "silk",
        areal_density: 0.05,
        stiffness: 40.0,
        damping: 0.004,
        shear_scale: 0.5,
        bend_scale: 0.05,
        drag_coefficient: 1.2,
        about: "light and limp: flutters in the least wind",
    },
    Material {
        name: "cotton",
        areal_density: 0.15,
        stiffness: 80.0,
        damping: 0.01,
        shear_scale: 1.0,
        bend_scale: 0.3,
        drag_coefficient: 1.0,
        about: "a shirt's weight, soft folds",
    },
    Material {
        name: "denim",
        areal_density: 0.4,
        stiffness: 200.0,
        damping: 0.03,
        shear_scale: 1.0,
        bend_scale: 1.0,
        drag_coefficient: 0.9,
        about: "heavy and firm: broad folds",
    },
    Material {
        name: "leather",
        areal_density: 1.0,
        stiffness: 600.0,
        damping: 0.1,
        shear_scale: 1.5,
        bend_scale: 2.0,
        drag_coefficient: 0.8,
        about: "heavy and stiff: holds its shape, the wind barely moves it",
    },
    Material {
        name: "rubber",
        areal_density: 1.2,
        stiffness: 30.0,
        damping: 0.004,
        shear_scale: 1.0,
        bend_scale: 0.5,
        drag_coefficient: 0.8,
        about: "a rubber sheet: heavy, stretchy and bouncy",
    },
];

impl Material {
    /// The built-in material called `name`.
    pub fn named(name: &str) -> Option<&'static Material> {
        MATERIALS.iter().find(|m| m.name == name)
    }

    /// Its mass per area, stiffness, damping, shear and bend scales and drag
    /// coefficient, in the order of the keys that give them.
    fn values(&self) -> [f64; 6] {
        [
            self.areal_density,
            self.stiffness,
            self.damping,
            self.shear_scale,
            self.bend_scale,
            self.drag_coefficient,
        ]
    }

    /// The names of the built-in materials, for error messages.
    pub fn names() -> String {
        let names: Vec<_> = MATERIALS
            .iter()
            .map(|m| format!("\"{}\"", m.name))
            .collect();
        names.join(", ")
    }
}

impl SceneSpec {
    /// The keys of each of a material's quantities, in [`Material::values`]'
    /// order: first the material's own key, then those that give the same
    /// quantity in other terms.
    fn material_keys(&mut self) -> [Vec<&mut Option<f64>>; 6] {
        [
            vec![
                &mut self.areal_density,
                &mut self.particle_mass,
                &mut self.total_mass,
            ],
            vec![&mut self.stiffness, &mut self.stiffness_per_mass],
            vec![
                &mut self.damping,
                &mut self.damping_ratio,
                &mut self.damping_per_mass,
            ],
            vec![&mut self.shear_scale],
            vec![&mut self.bend_scale],
            vec![&mut self.drag_coefficient],
        ]
    }

    /// `self` with its material's properties filled in where the scene gives none
    /// of the keys for that quantity (a scene file's own `stiffness` next to
    /// `material` holds); `shear_scale` only on a grid, the one layout with shear
    /// springs.
    pub(crate) fn with_material(&self, material: &Material) -> SceneSpec {
        let mut spec = self.clone();
        let grid = spec.layout == super::Layout::Grid;
        let keys = spec.material_keys();
        for (i, (mut group, value)) in keys.into_iter().zip(material.values()).enumerate() {
            let shear = i == 3;
            if group.iter().all(|k| k.is_none()) && (grid || !shear) {
                *group[0] = Some(value);
            }
        }
        spec
    }

    /// Whether the scene gives one of its material's quantities itself (a slider
    /// moved after the material was chosen).
    pub fn overrides_material(&self) -> bool {
        let mut spec = self.clone();
        spec.material.is_some()
            && (spec.material_keys().iter()).any(|group| group.iter().any(|k| k.is_some()))
    }

    /// Makes `material` the scene's, dropping every key that gives one of its
    /// quantities so that its values hold. A grid keeps its size in m (`size`)
    /// rather than its spacing, so that a change of width then refines the same
    /// cloth.
    pub(crate) fn take_material(&mut self, material: &Material) {
        self.material = Some(material.name.to_string());
        for group in self.material_keys() {
            for key in group {
                *key = None;
            }
        }
        if let (super::Layout::Grid, Some(rest), Some(width)) =
            (self.layout, self.rest_length, self.width)
        {
            self.rest_length = None;
            self.size = Some(rest * f64::from(width.max(2) - 1));
        }
    }
}
