//! ROS 2 message definitions (`.msg` text): the field list of each type a bag's
//! messages are decoded by. An MCAP bag stores them as its schema records (the type's
//! own fields, then each type it uses after a line of `=` and `MSG: pkg/Type`); a
//! sqlite3 bag stores none, so the definitions of the types this tool reads are carried
//! here ([`CARRIED`]). Constants and comments are skipped; a field's type is a
//! primitive, a string, or another type, each alone, in a fixed array (`T[4]`) or in a
//! sequence (`T[]`, `T[<=N]`).
//! In: definition text. Out: [`Definitions`], each type by its full name
//! (`geometry_msgs/msg/Vector3`), or a [`DefinitionError`] naming the line.

use std::collections::BTreeMap;

/// A primitive's kind: its size in bytes in CDR, and how it reads.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Primitive {
    Bool,
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    I64,
    U64,
    F32,
    F64,
}

impl Primitive {
    fn named(name: &str) -> Option<Primitive> {
        Some(match name {
            "bool" => Primitive::Bool,
            "int8" => Primitive::I8,
            "uint8" | "byte" | "char" => Primitive::U8,
            "int16" => Primitive::I16,
            "uint16" => Primitive::U16,
            "int32" => Primitive::I32,
            "uint32" => Primitive::U32,
            "int64" => Primitive::I64,
            "uint64" => Primitive::U64,
            "float32" => Primitive::F32,
            "float64" => Primitive::F64,
            _ => return None,
        })
    }

    /// Its size in bytes, which is also its alignment in CDR.
    pub fn size(self) -> usize {
        match self {
            Primitive::Bool | Primitive::I8 | Primitive::U8 => 1,
            Primitive::I16 | Primitive::U16 => 2,
            Primitive::I32 | Primitive::U32 | Primitive::F32 => 4,
            Primitive::I64 | Primitive::U64 | Primitive::F64 => 8,
        }
    }
}

/// What one element of a field holds.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Element {
    Primitive(Primitive),
    /// A string or wstring (read as bytes).
    Text,
    /// Another message type, by its full name.
    Message(String),
}

/// How many elements a field holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Count {
    One,
    Fixed(usize),
    /// A sequence, its length before its elements.
    Sequence,
}

#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Field {
    pub name: String,
    pub element: Element,
    pub count: Count,
}

/// Message types by full name, each with its fields in order.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Definitions {
    pub types: BTreeMap<String, Vec<Field>>,
}

#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("the definition of {type_name}, line {line}: {problem}")]
pub struct DefinitionError {
    pub type_name: String,
    pub line: usize,
    pub problem: String,
}

/// `pkg/Type` or `pkg/msg/Type` as `pkg/msg/Type`.
pub fn full_name(name: &str) -> String {
    let parts: Vec<&str> = name.split('/').collect();
    match parts.as_slice() {
        [package, type_name] => format!("{package}/msg/{type_name}"),
        _ => name.to_string(),
    }
}

impl Definitions {
    /// The definitions in `text`, the first of them `type_name`'s, as an MCAP schema
    /// record holds them; added to those already here.
    pub fn add(&mut self, type_name: &str, text: &str) -> Result<(), DefinitionError> {
        let mut current = full_name(type_name);
        let mut fields = Vec::new();
        // Each field's line, for a type found to hold itself.
        let mut lines: BTreeMap<(String, String), usize> = BTreeMap::new();
        for (number, line) in text.lines().enumerate() {
            let line = line.split('#').next().unwrap_or("").trim();
            if line.starts_with("===") {
                self.types
                    .insert(std::mem::take(&mut current), std::mem::take(&mut fields));
                continue;
            }
            if let Some(name) = line.strip_prefix("MSG:") {
                current = full_name(name.trim());
                continue;
            }
            if line.is_empty() {
                continue;
            }
            let error = |problem: &str| DefinitionError {
                type_name: current.clone(),
                line: number + 1,
                problem: problem.to_string(),
            };
            let mut words = line.split_whitespace();
            let (Some(kind), Some(name)) = (words.next(), words.next()) else {
                return Err(error("a field needs a type and a name"));
            };
            if name.contains('=') || words.next().is_some_and(|w| w.starts_with('=')) {
                continue; // a constant
            }
            fields.push(field(kind, name, &current).map_err(|p| error(&p))?);
            lines.insert((current.clone(), name.to_string()), number + 1);
        }
        self.types.insert(current, fields);
        match self.holding_itself(&full_name(type_name), &mut Vec::new(), &mut Vec::new()) {
            Some((holder, field, held)) => Err(DefinitionError {
                line: lines
                    .get(&(holder.clone(), field.clone()))
                    .copied()
                    .unwrap_or(0),
                problem: match held == holder {
                    true => format!("field {field} is of type {held} itself"),
                    false => {
                        format!("field {field} is of type {held}, which holds {holder} in turn")
                    }
                } + ": a type that holds itself has no end, and no ROS message is one",
                type_name: holder,
            }),
            None => Ok(()),
        }
    }

    /// The first type on the way from `type_name` that holds a type it lies within
    /// (`within`, the types on the way): that type, its field and the type it holds.
    /// Each type is walked once (`done`, those whose every way was walked).
    fn holding_itself(
        &self,
        type_name: &str,
        within: &mut Vec<String>,
        done: &mut Vec<String>,
    ) -> Option<(String, String, String)> {
        within.push(type_name.to_string());
        for field in self.fields(type_name).into_iter().flatten() {
            let Element::Message(inner) = &field.element else {
                continue;
            };
            let inner = full_name(inner);
            if within.contains(&inner) {
                return Some((type_name.to_string(), field.name.clone(), inner));
            }
            if done.contains(&inner) {
                continue;
            }
            if let Some(found) = self.holding_itself(&inner, within, done) {
                return Some(found);
            }
        }
        within.pop();
        done.push(type_name.to_string());
        None
    }

    /// The fields of `type_name` (either spelling), where it is defined.
    pub fn fields(&self, type_name: &str) -> Option<&[Field]> {
        self.types.get(&full_name(type_name)).map(Vec::as_slice)
    }

    /// Whether `type_name` has a field at each dotted path of `paths`, such as
    /// `header.stamp.sec`.
    pub fn has_paths(&self, type_name: &str, paths: &[&str]) -> bool {
        paths
            .iter()
            .all(|path| self.path(type_name, path).is_some())
    }

    /// The field at the dotted `path` of `type_name`: the index of each field on the
    /// way, and the last field.
    pub fn path(&self, type_name: &str, path: &str) -> Option<(Vec<usize>, &Field)> {
        let mut fields = self.fields(type_name)?;
        let mut indices = Vec::new();
        let mut parts = path.split('.').peekable();
        while let Some(part) = parts.next() {
            let at = fields.iter().position(|f| f.name == part)?;
            indices.push(at);
            let field = &fields[at];
            if parts.peek().is_none() {
                return Some((indices, field));
            }
            match (&field.element, field.count) {
                (Element::Message(inner), Count::One) => fields = self.fields(inner)?,
                _ => return None,
            }
        }
        None
    }

    /// The definitions of the types this tool reads, for a bag that stores none.
    pub fn carried() -> Definitions {
        let mut definitions = Definitions::default();
        definitions
            .add("carried", CARRIED)
            .expect("the carried definitions parse");
        definitions.types.remove("carried");
        definitions
    }
}

/// The longest fixed array read: a schema with a longer one is damaged.
const MAX_FIXED_LENGTH: usize = 1 << 20;

/// One field's type `kind` and `name`, in a definition of the package of `within`.
fn field(kind: &str, name: &str, within: &str) -> Result<Field, String> {
    let (base, count) = match kind.split_once('[') {
        None => (kind, Count::One),
        Some((base, rest)) => {
            let inside = rest
                .strip_suffix(']')
                .ok_or(format!("{kind}: no closing ]"))?;
            let count = if inside.is_empty() || inside.starts_with("<=") {
                Count::Sequence
            } else {
                let length: usize =
                    (inside.parse()).map_err(|_| format!("{kind}: not an array length"))?;
                if length > MAX_FIXED_LENGTH {
                    return Err(format!(
                        "{kind}: an array of {length} elements, beyond any message's"
                    ));
                }
                Count::Fixed(length)
            };
            (base, count)
        }
    };
    let base = base.split("<=").next().unwrap_or(base);
    let element = if let Some(primitive) = Primitive::named(base) {
        Element::Primitive(primitive)
    } else if base == "string" || base == "wstring" {
        Element::Text
    } else if base == "Header" {
        Element::Message("std_msgs/msg/Header".into())
    } else if base.contains('/') {
        Element::Message(full_name(base))
    } else {
        let package = within.split('/').next().unwrap_or("");
        Element::Message(format!("{package}/msg/{base}"))
    };
    Ok(Field {
        name: name.to_string(),
        element,
        count,
    })
}

/// The types this tool reads, and those they use, as their packages define them.
pub const CARRIED: &str = "\
================================================================================
MSG: builtin_interfaces/Time
int32 sec
uint32 nanosec
================================================================================
MSG: std_msgs/Header
builtin_interfaces/Time stamp
string frame_id
================================================================================
MSG: geometry_msgs/Vector3
float64 x
float64 y
float64 z
================================================================================
MSG: geometry_msgs/Point
float64 x
float64 y
float64 z
================================================================================
MSG: geometry_msgs/Quaternion
float64 x
float64 y
float64 z
float64 w
================================================================================
MSG: geometry_msgs/Pose
geometry_msgs/Point position
geometry_msgs/Quaternion orientation
================================================================================
MSG: geometry_msgs/PoseWithCovariance
geometry_msgs/Pose pose
float64[36] covariance
================================================================================
MSG: geometry_msgs/Twist
geometry_msgs/Vector3 linear
geometry_msgs/Vector3 angular
================================================================================
MSG: geometry_msgs/TwistWithCovariance
geometry_msgs/Twist twist
float64[36] covariance
================================================================================
MSG: geometry_msgs/TwistStamped
std_msgs/Header header
geometry_msgs/Twist twist
================================================================================
MSG: geometry_msgs/TwistWithCovarianceStamped
std_msgs/Header header
geometry_msgs/TwistWithCovariance twist
================================================================================
MSG: geometry_msgs/Transform
geometry_msgs/Vector3 translation
geometry_msgs/Quaternion rotation
================================================================================
MSG: geometry_msgs/TransformStamped
std_msgs/Header header
string child_frame_id
geometry_msgs/Transform transform
================================================================================
MSG: tf2_msgs/TFMessage
geometry_msgs/TransformStamped[] transforms
================================================================================
MSG: nav_msgs/Odometry
std_msgs/Header header
string child_frame_id
geometry_msgs/PoseWithCovariance pose
geometry_msgs/TwistWithCovariance twist
================================================================================
MSG: sensor_msgs/Imu
std_msgs/Header header
geometry_msgs/Quaternion orientation
float64[9] orientation_covariance
geometry_msgs/Vector3 angular_velocity
float64[9] angular_velocity_covariance
geometry_msgs/Vector3 linear_acceleration
float64[9] linear_acceleration_covariance
================================================================================
MSG: geometry_msgs/PoseWithCovarianceStamped
std_msgs/Header header
geometry_msgs/PoseWithCovariance pose
================================================================================
MSG: sensor_msgs/NavSatStatus
int8 STATUS_NO_FIX=-1
int8 STATUS_FIX=0
int8 STATUS_SBAS_FIX=1
int8 STATUS_GBAS_FIX=2
int8 status
uint16 SERVICE_GPS=1
uint16 SERVICE_GLONASS=2
uint16 SERVICE_COMPASS=4
uint16 SERVICE_GALILEO=8
uint16 service
================================================================================
MSG: sensor_msgs/NavSatFix
std_msgs/Header header
sensor_msgs/NavSatStatus status
float64 latitude
float64 longitude
float64 altitude
float64[9] position_covariance
uint8 COVARIANCE_TYPE_UNKNOWN=0
uint8 COVARIANCE_TYPE_APPROXIMATED=1
uint8 COVARIANCE_TYPE_DIAGONAL_KNOWN=2
uint8 COVARIANCE_TYPE_KNOWN=3
uint8 position_covariance_type
================================================================================
MSG: marine_acoustic_msgs/Dvl
uint8 DVL_MODE_BOTTOM=1
uint8 DVL_MODE_WATER=2
uint8 DVL_TYPE_PISTON=0
uint8 DVL_TYPE_PHASED_ARRAY=1
std_msgs/Header header
uint8 velocity_mode
uint8 dvl_type
geometry_msgs/Vector3 velocity
float64[9] velocity_covar
float64 altitude
float64 course_gnd
float64 speed_gnd
uint8 num_good_beams
float32 sound_speed
bool beam_ranges_valid
bool beam_velocities_valid
geometry_msgs/Vector3[4] beam_unit_vec
float64[4] range
float32[4] range_covar
float32[4] beam_quality
float32[4] beam_velocity
float32[4] beam_velocity_covar
";

/// The definition of `type_name` as an MCAP schema record of a ROS 2 bag holds it:
/// its own fields, then every type it uses, from the carried definitions.
pub fn schema_text(type_name: &str) -> String {
    let carried = Definitions::carried();
    let name = full_name(type_name);
    let mut order = vec![name.clone()];
    let mut at = 0;
    while at < order.len() {
        for field in carried.types.get(&order[at]).into_iter().flatten() {
            if let Element::Message(inner) = &field.element
                && !order.contains(inner)
            {
                order.push(inner.clone());
            }
        }
        at += 1;
    }
    let section = |name: &str| -> String {
        let section = CARRIED
            .split("================================================================================\n")
            .find(|s| s.lines().next().is_some_and(|l| full_name(l.trim_start_matches("MSG: ")) == name))
            .unwrap_or("");
        section.lines().skip(1).map(|l| format!("{l}\n")).collect()
    };
    let mut text = section(&name);
    for inner in &order[1..] {
        let short = inner.replace("/msg/", "/");
        text.push_str(&format!(
            "{}\nMSG: {short}\n{}",
            "=".repeat(80),
            section(inner)
        ));
    }
    text
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The carried definitions read, with constants skipped and arrays counted; a
    /// schema made from them reads back to the same fields.
    #[test]
    fn definitions_are_read_with_their_arrays_and_without_constants() {
        let carried = Definitions::carried();
        let dvl = carried.fields("marine_acoustic_msgs/Dvl").unwrap();
        assert_eq!(dvl[0].name, "header");
        assert_eq!(dvl.len(), 18);
        let beams = dvl.iter().find(|f| f.name == "beam_unit_vec").unwrap();
        assert_eq!(beams.count, Count::Fixed(4));
        assert_eq!(
            beams.element,
            Element::Message("geometry_msgs/msg/Vector3".into())
        );
        let tf = carried.fields("tf2_msgs/msg/TFMessage").unwrap();
        assert_eq!(tf[0].count, Count::Sequence);
        let (indices, field) = carried
            .path("nav_msgs/msg/Odometry", "twist.twist.angular.z")
            .unwrap();
        assert_eq!(indices, vec![3, 0, 1, 2]);
        assert_eq!(field.element, Element::Primitive(Primitive::F64));
        assert!(
            carried
                .path("nav_msgs/msg/Odometry", "twist.nothing")
                .is_none()
        );
        let mut from_schema = Definitions::default();
        from_schema
            .add(
                "nav_msgs/msg/Odometry",
                &schema_text("nav_msgs/msg/Odometry"),
            )
            .unwrap();
        for name in [
            "nav_msgs/msg/Odometry",
            "geometry_msgs/msg/Quaternion",
            "builtin_interfaces/msg/Time",
        ] {
            assert_eq!(from_schema.fields(name), carried.fields(name), "{name}");
        }
        let error = Definitions::default()
            .add("a/B", "float64[99999999999] x\n")
            .unwrap_err();
        assert!(
            error
                .to_string()
                .contains("an array of 99999999999 elements, beyond any message's"),
            "{error}"
        );
        let error = Definitions::default().add("a/B", "float64\n").unwrap_err();
        assert_eq!(
            error.to_string(),
            "the definition of a/msg/B, line 1: a field needs a type and a name"
        );
    }
}
