//! Units and the request's named choices: the mesh file's unit, the implant's outline, the
//! region rule, the broad phase, the solver and the field a picture is coloured by.
//!
//! Inside, everything runs in centimetres, grams and seconds; a patient file is scaled to cm on
//! load and outputs go back to its unit ([`Unit::cm_per_unit`]).

use serde::{Deserialize, Serialize};

/// One kPa in the libraries' unit of stress, g/(cm·s²) (1 Pa = 10 g/(cm·s²)).
pub const KPA: f64 = 1.0e4;

/// The mesh file's unit of length.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
#[serde(rename_all = "lowercase")]
pub enum Unit {
    /// Millimetres.
    Mm,
    /// Centimetres.
    #[default]
    Cm,
    /// Decimetres (the MakeHuman meshes).
    Dm,
    /// Metres.
    M,
}

impl Unit {
    /// Every unit, smallest first.
    pub const ALL: [Unit; 4] = [Unit::Mm, Unit::Cm, Unit::Dm, Unit::M];

    /// Centimetres per unit.
    pub fn cm_per_unit(self) -> f32 {
        match self {
            Unit::Mm => 0.1,
            Unit::Cm => 1.0,
            Unit::Dm => 10.0,
            Unit::M => 100.0,
        }
    }

    /// The unit's symbol (`mm`, `cm`, `dm`, `m`), as the JSON has it.
    pub fn symbol(self) -> &'static str {
        match self {
            Unit::Mm => "mm",
            Unit::Cm => "cm",
            Unit::Dm => "dm",
            Unit::M => "m",
        }
    }

    /// The unit of `symbol`, or `None`.
    pub fn from_symbol(symbol: &str) -> Option<Unit> {
        Unit::ALL.into_iter().find(|u| u.symbol() == symbol)
    }
}

/// The implant's base outline.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
#[serde(rename_all = "lowercase")]
pub enum Shape {
    /// Circular base: `diameter_cm`.
    #[default]
    Round,
    /// Rectangular base: `length_cm` × `width_cm`, corners rounded to `corner_radius_cm`.
    Rectangular,
    /// Crescent (kidney) base: `length_cm` (tip to tip), `width_cm`, `bend_radius_cm`.
    Crescent,
}

impl Shape {
    /// The shape's name, as the JSON has it.
    pub fn name(self) -> &'static str {
        match self {
            Shape::Round => "round",
            Shape::Rectangular => "rectangular",
            Shape::Crescent => "crescent",
        }
    }
}

/// Which triangles within the region radius form the region.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
#[serde(rename_all = "kebab-case")]
pub enum Rule {
    /// Every triangle with a corner within the radius (the thesis's rule, Table 2).
    #[default]
    TouchesVertex,
    /// Triangles whose mean corner distance is within the radius (area ≈ πr²).
    Centroid,
}

impl Rule {
    /// The rule's name, as the JSON has it.
    pub fn name(self) -> &'static str {
        match self {
            Rule::TouchesVertex => "touches-vertex",
            Rule::Centroid => "centroid",
        }
    }
}

/// The collision broad phase.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
#[serde(rename_all = "lowercase")]
pub enum Detect {
    /// A bounding-volume hierarchy over both surfaces.
    #[default]
    Bvh,
    /// A hierarchy over the tissue, a voxel grid over the implant.
    Voxels,
}

impl Detect {
    /// The broad phase's name, as the JSON has it.
    pub fn name(self) -> &'static str {
        match self {
            Detect::Bvh => "bvh",
            Detect::Voxels => "voxels",
        }
    }
}

/// How a run finds the tissue's rest state over the filled expander (`solver`): the request's
/// choice, `inputs.solver` in the report, `insert --solver`. [`tissue_implant::Solver`] in the
/// planner's JSON names.
///
/// Read from JSON by name only; an unknown name is refused naming the field and the names
/// (`` unknown variant `x` of `solver`, expected `explicit` or `quasi_static` ``).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
#[cfg_attr(feature = "clap", value(rename_all = "snake_case"))]
#[serde(rename_all = "snake_case")]
pub enum Solver {
    /// Steps the thesis's explicit Euler until the stop criterion fires (the default and the
    /// reference).
    #[default]
    Explicit,
    /// Solves for the static equilibrium directly (experimental).
    QuasiStatic,
}

impl Solver {
    /// Every solver, the default first.
    pub const ALL: [Solver; 2] = [Solver::Explicit, Solver::QuasiStatic];

    /// The solver's name, as the JSON and the command line have it: `quasi_static`, `explicit`.
    pub fn name(self) -> &'static str {
        tissue_implant::Solver::from(self).name()
    }

    /// The solver of `name`, or `None`.
    pub fn from_name(name: &str) -> Option<Solver> {
        Solver::ALL.into_iter().find(|s| s.name() == name)
    }
}

impl From<Solver> for tissue_implant::Solver {
    fn from(solver: Solver) -> Self {
        match solver {
            Solver::QuasiStatic => tissue_implant::Solver::QuasiStatic,
            Solver::Explicit => tissue_implant::Solver::Explicit,
        }
    }
}

impl From<tissue_implant::Solver> for Solver {
    /// Exhaustive on purpose: a new library solver must be given its JSON name here.
    fn from(solver: tissue_implant::Solver) -> Self {
        match solver {
            tissue_implant::Solver::QuasiStatic => Solver::QuasiStatic,
            tissue_implant::Solver::Explicit => Solver::Explicit,
        }
    }
}

impl<'de> Deserialize<'de> for Solver {
    /// By name, refusing an unknown one with the field's name and the names it takes.
    fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        let name = String::deserialize(deserializer)?;
        Solver::from_name(&name).ok_or_else(|| {
            let names: Vec<String> = Solver::ALL
                .iter()
                .map(|s| format!("`{}`", s.name()))
                .collect();
            serde::de::Error::custom(format!(
                "unknown variant `{name}` of `solver`, expected {}",
                names.join(" or ")
            ))
        })
    }
}

/// The per-vertex field that colours a picture of the result.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
#[serde(rename_all = "lowercase")]
pub enum ColorBy {
    /// How far each vertex moved (mesh unit).
    #[default]
    Displacement,
    /// Area after / area before of the skin around each vertex.
    Stretch,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn symbols_round_trip_and_scale() {
        for u in Unit::ALL {
            assert_eq!(Unit::from_symbol(u.symbol()), Some(u));
            let json = serde_json::to_string(&u).unwrap_or_default();
            assert_eq!(json, format!("\"{}\"", u.symbol()));
        }
        assert_eq!(Unit::Mm.cm_per_unit() * 10.0, Unit::Cm.cm_per_unit());
        assert_eq!(Unit::from_symbol("inch"), None);
        let rule: Result<Rule, _> = serde_json::from_str("\"touches-vertex\"");
        assert_eq!(rule.ok(), Some(Rule::TouchesVertex));
    }

    /// The solver's names are the library's, both ways, and an unknown one is refused naming
    /// the field and every name.
    #[test]
    fn solver_names_are_the_librarys_and_an_unknown_one_names_the_field() {
        for s in Solver::ALL {
            let library = tissue_implant::Solver::from(s);
            assert_eq!(Solver::from(library), s);
            assert_eq!(s.name(), library.name());
            let json = serde_json::to_string(&s).unwrap_or_default();
            assert_eq!(json, format!("\"{}\"", s.name()));
            let back: Result<Solver, _> = serde_json::from_str(&json);
            assert_eq!(back.ok(), Some(s));
        }
        assert_eq!(Solver::default(), Solver::Explicit);
        assert_eq!(
            tissue_implant::Solver::from(Solver::default()),
            tissue_implant::Solver::default()
        );
        assert_eq!(Solver::ALL.map(Solver::name), ["explicit", "quasi_static"]);
        let unknown = serde_json::from_str::<Solver>("\"quasi-static\"")
            .err()
            .map(|e| e.to_string())
            .unwrap_or_default();
        assert!(
            unknown.contains("`quasi-static` of `solver`, expected `explicit` or `quasi_static`"),
            "{unknown}"
        );
        assert!(serde_json::from_str::<Solver>("1").is_err());
    }
}
