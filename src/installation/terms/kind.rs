//! The kinds of term, one table row each ([`KindOfTerm`]): the name a spec's keys use,
//! the name people read, its parameters' names in their stored units, the unit its
//! values are shown in (and the spec's keys written in), where its values sit in an
//! [`Installation`], and its column of the prediction's Jacobian. Each row lives in the
//! file of its kind (`scale.rs`, `misalignment.rs`, `lever_arm.rs`, `time_offset.rs`,
//! `bias.rs`), and [`TermKind::table`], in the folder's `mod.rs`, finds it; everything that walks the terms (parameter names and vectors, the
//! Jacobian, the units of a table, the network's outputs, a spec's tolerance keys)
//! walks [`TermKind::ALL`] through them. In: a kind, or a parameter's name. Out: its row.

use crate::Vec3;
use crate::installation::terms::{Installation, Linearisation};

/// What kind of term a parameter belongs to (its unit and its tolerance follow).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum TermKind {
    /// A fraction: 0.01 is 1 %.
    Scale,
    /// Radians.
    Misalignment,
    /// Metres.
    LeverArm,
    /// Seconds.
    TimeOffset,
    /// m/s.
    Bias,
}

impl TermKind {
    /// Every kind, in the order of a parameter vector.
    pub const ALL: [TermKind; 5] = [
        TermKind::Scale,
        TermKind::Misalignment,
        TermKind::LeverArm,
        TermKind::TimeOffset,
        TermKind::Bias,
    ];

    /// The kind and the axis (`None` for one value on all axes) of a parameter named as
    /// [`TermSet::parameter_names`](crate::installation::terms::TermSet::parameter_names)
    /// names it; `None` for a name no kind gives.
    pub fn of_parameter(name: &str) -> Option<(&'static KindOfTerm, Option<usize>)> {
        TermKind::ALL.into_iter().find_map(|kind| {
            let row = kind.table();
            if row.one_name == Some(name) {
                return Some((row, None));
            }
            let axis = row.axis_names?.iter().position(|n| *n == name)?;
            Some((row, Some(axis)))
        })
    }
}

/// One kind of term, as every part of the tool names, shows and differentiates it.
pub struct KindOfTerm {
    pub kind: TermKind,
    /// Its name in a spec's keys: `lever_arm` in `prior_lever_arm_m` and
    /// `observability.lever_arm_m`.
    pub key: &'static str,
    /// Its name for people: `lever arm`.
    pub readable: &'static str,
    /// Its parameter's name when one value stands for every axis (`time_offset_s`,
    /// `bias_m_s`); `None` for a kind that is always per axis.
    pub one_name: Option<&'static str>,
    /// Its parameters' names per axis x, y, z (`lever_arm_x_m`); `None` for a kind with
    /// one value only.
    pub axis_names: Option<[&'static str; 3]>,
    /// The unit its values are shown in, and a spec gives them in.
    pub unit: ShownUnit,
    /// Its values in an installation, per axis (a kind with one value: that value on
    /// the x axis).
    pub(in crate::installation::terms) values: fn(&Installation) -> Vec3,
    /// Sets its values in an installation, per axis (a kind with one value: from x).
    pub(in crate::installation::terms) set: fn(&mut Installation, Vec3),
    /// ∂prediction/∂parameter, a velocity in m/s per stored unit: of the parameter on
    /// `axis`, or of the one value on every axis (`None`).
    pub(in crate::installation::terms) column: fn(&Linearisation, Option<usize>) -> Vec3,
}

impl KindOfTerm {
    /// The spec key of a value of this kind in its shown unit, after `prefix`
    /// (`prior_` gives `prior_lever_arm_m`; an empty one `lever_arm_m`).
    pub fn spec_key(&self, prefix: &str) -> String {
        format!("{prefix}{}_{}", self.key, self.unit.key())
    }

    /// A parameter's name for people: the kind's, with its axis (`lever arm x`).
    pub fn readable_name(&self, axis: Option<usize>) -> String {
        match axis {
            Some(axis) => format!("{} {}", self.readable, ["x", "y", "z"][axis]),
            None => self.readable.to_string(),
        }
    }
}

/// The unit a kind of term is shown in, in tables, figures, printed lines, a spec's
/// keys and the learned network's outputs (each near 1 for a real installation).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ShownUnit {
    /// Per cent, of a fraction stored.
    Percent,
    /// Degrees, of radians stored.
    Degrees,
    /// Metres, as stored.
    Metres,
    /// Seconds, as stored.
    Seconds,
    /// cm/s, of m/s stored.
    CentimetresPerSecond,
}

impl ShownUnit {
    /// The unit as a table shows it: `%`, `deg`, `m`, `s`, `cm/s`.
    pub fn symbol(self) -> &'static str {
        match self {
            ShownUnit::Percent => "%",
            ShownUnit::Degrees => "deg",
            ShownUnit::Metres => "m",
            ShownUnit::Seconds => "s",
            ShownUnit::CentimetresPerSecond => "cm/s",
        }
    }

    /// The unit as a spec key ends: `pct`, `deg`, `m`, `s`, `cm_s`.
    pub fn key(self) -> &'static str {
        match self {
            ShownUnit::Percent => "pct",
            ShownUnit::Degrees => "deg",
            ShownUnit::Metres => "m",
            ShownUnit::Seconds => "s",
            ShownUnit::CentimetresPerSecond => "cm_s",
        }
    }

    /// The factor from the stored value to the shown one: shown = stored × factor.
    pub fn factor(self) -> f64 {
        match self {
            ShownUnit::Percent | ShownUnit::CentimetresPerSecond => 100.0,
            ShownUnit::Degrees => 180.0 / std::f64::consts::PI,
            ShownUnit::Metres | ShownUnit::Seconds => 1.0,
        }
    }

    /// A shown value (as a spec gives it) in the stored unit.
    pub fn to_stored(self, shown: f64) -> f64 {
        match self {
            ShownUnit::Percent | ShownUnit::CentimetresPerSecond => shown / 100.0,
            ShownUnit::Degrees => shown.to_radians(),
            ShownUnit::Metres | ShownUnit::Seconds => shown,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_parameter_name_leads_back_to_its_kind_and_axis() {
        for kind in TermKind::ALL {
            let row = kind.table();
            assert_eq!(row.kind, kind);
            if let Some(name) = row.one_name {
                assert_eq!(
                    TermKind::of_parameter(name).map(|(r, a)| (r.kind, a)),
                    Some((kind, None))
                );
            }
            for (axis, name) in row.axis_names.into_iter().flatten().enumerate() {
                let found = TermKind::of_parameter(name).map(|(r, a)| (r.kind, a));
                assert_eq!(found, Some((kind, Some(axis))));
            }
        }
        assert!(TermKind::of_parameter("lever_arm_m").is_none());
    }

    #[test]
    fn spec_keys_and_shown_values_are_the_specs() {
        let keys: Vec<String> = TermKind::ALL.map(|k| k.table().spec_key("")).to_vec();
        assert_eq!(
            keys,
            [
                "scale_pct",
                "misalignment_deg",
                "lever_arm_m",
                "time_offset_s",
                "bias_cm_s"
            ]
        );
        assert_eq!(TermKind::Bias.table().spec_key("prior_"), "prior_bias_cm_s");
        for kind in TermKind::ALL {
            let unit = kind.table().unit;
            let shown = 0.5;
            assert!(
                (unit.to_stored(shown) * unit.factor() - shown).abs() < 1e-15,
                "{kind:?}"
            );
        }
    }
}
