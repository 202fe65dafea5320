//! CDR, the byte layout of a ROS 2 message: a 4-byte header that says the byte order,
//! then each field in order, each primitive aligned to its size from the header's end,
//! a string or a sequence after its 4-byte length. [`decode`] reads a message into a
//! [`Value`] by its [`Definitions`]; [`Encoder`] writes one, for the bags this tool
//! writes and those its tests write.
//! In: a message's bytes and its type's definitions. Out: its [`Value`], or where the
//! bytes run out or cannot be read.

use super::definitions::{Count, Definitions, Element, Field, Primitive};

/// A decoded message: numbers (booleans and integers as f64), text, and the fields of
/// an inner message or the elements of an array, in order.
#[derive(Debug, Clone, PartialEq)]
pub enum Value {
    Number(f64),
    Text(String),
    List(Vec<Value>),
}

impl Value {
    /// The value at `indices`, each an index into a list (a message's fields or an
    /// array's elements).
    pub fn at(&self, indices: &[usize]) -> Option<&Value> {
        indices.iter().try_fold(self, |value, &k| match value {
            Value::List(items) => items.get(k),
            _ => None,
        })
    }

    pub fn number(&self) -> Option<f64> {
        match self {
            Value::Number(n) => Some(*n),
            _ => None,
        }
    }

    pub fn text(&self) -> Option<&str> {
        match self {
            Value::Text(t) => Some(t),
            _ => None,
        }
    }
}

#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum CdrError {
    #[error("the message ends at byte {at} where {type_name}.{field} needs {needs} more")]
    Short {
        at: usize,
        type_name: String,
        field: String,
        needs: usize,
    },
    #[error(
        "its encapsulation {0:#06x} is not plain CDR (0x0000 big-endian, 0x0001 little-endian)"
    )]
    Encapsulation(u16),
    #[error("{0} is not defined in the bag's schema")]
    Undefined(String),
    #[error("{0} lies more than 32 messages deep: a type that holds itself")]
    Nested(String),

    #[error("{type_name}.{field}: a sequence of {count} elements is longer than the message")]
    Length {
        type_name: String,
        field: String,
        count: usize,
    },
}

/// The message `bytes` of type `type_name`, read by `definitions`.
pub fn decode(bytes: &[u8], type_name: &str, definitions: &Definitions) -> Result<Value, CdrError> {
    if bytes.len() < 4 {
        return Err(CdrError::Short {
            at: bytes.len(),
            type_name: type_name.into(),
            field: "(header)".into(),
            needs: 4 - bytes.len(),
        });
    }
    let encapsulation = u16::from_be_bytes([bytes[0], bytes[1]]);
    let little = match encapsulation {
        0x0000 => false,
        0x0001 => true,
        other => return Err(CdrError::Encapsulation(other)),
    };
    let mut reader = Reader {
        bytes: &bytes[4..],
        at: 0,
        little,
        definitions,
        depth: 0,
    };
    reader.message(type_name)
}

struct Reader<'a> {
    bytes: &'a [u8],
    at: usize,
    little: bool,
    definitions: &'a Definitions,
    /// How many messages deep the reading is.
    depth: usize,
}

/// The deepest nesting of messages read: deeper is a type that holds itself.
const MAX_DEPTH: usize = 32;

impl Reader<'_> {
    fn message(&mut self, type_name: &str) -> Result<Value, CdrError> {
        self.depth += 1;
        if self.depth > MAX_DEPTH {
            return Err(CdrError::Nested(type_name.to_string()));
        }
        let fields = (self.definitions.fields(type_name))
            .ok_or_else(|| CdrError::Undefined(type_name.to_string()))?;
        let mut values = Vec::with_capacity(fields.len());
        for field in fields {
            values.push(self.field(type_name, field)?);
        }
        self.depth -= 1;
        Ok(Value::List(values))
    }

    fn field(&mut self, type_name: &str, field: &Field) -> Result<Value, CdrError> {
        let count = match field.count {
            Count::One => return self.element(type_name, field),
            Count::Fixed(n) => n,
            Count::Sequence => {
                let n = self.primitive(type_name, field, Primitive::U32)? as usize;
                if n > self.bytes.len() - self.at {
                    return Err(CdrError::Length {
                        type_name: type_name.into(),
                        field: field.name.clone(),
                        count: n,
                    });
                }
                n
            }
        };
        let mut items = Vec::with_capacity(count.min(self.bytes.len() - self.at));
        for _ in 0..count {
            items.push(self.element(type_name, field)?);
        }
        Ok(Value::List(items))
    }

    fn element(&mut self, type_name: &str, field: &Field) -> Result<Value, CdrError> {
        match &field.element {
            Element::Primitive(primitive) => self
                .primitive(type_name, field, *primitive)
                .map(Value::Number),
            Element::Text => {
                let length = self.primitive(type_name, field, Primitive::U32)? as usize;
                let bytes = self.take(type_name, field, length)?;
                let text = bytes.strip_suffix(&[0]).unwrap_or(bytes);
                Ok(Value::Text(String::from_utf8_lossy(text).into_owned()))
            }
            Element::Message(inner) => self.message(inner),
        }
    }

    fn take(&mut self, type_name: &str, field: &Field, n: usize) -> Result<&[u8], CdrError> {
        if self.bytes.len() - self.at < n {
            return Err(CdrError::Short {
                at: self.bytes.len() + 4,
                type_name: type_name.into(),
                field: field.name.clone(),
                needs: n - (self.bytes.len() - self.at),
            });
        }
        self.at += n;
        Ok(&self.bytes[self.at - n..self.at])
    }

    fn primitive(
        &mut self,
        type_name: &str,
        field: &Field,
        kind: Primitive,
    ) -> Result<f64, CdrError> {
        let size = kind.size();
        let padding = (size - self.at % size) % size;
        self.take(type_name, field, padding)?;
        let little = self.little;
        let raw = self.take(type_name, field, size)?;
        let mut buffer = [0u8; 8];
        buffer[..size].copy_from_slice(raw);
        if !little {
            buffer[..size].reverse();
        }
        Ok(match kind {
            Primitive::Bool | Primitive::U8 => buffer[0] as f64,
            Primitive::I8 => buffer[0] as i8 as f64,
            Primitive::I16 => i16::from_le_bytes([buffer[0], buffer[1]]) as f64,
            Primitive::U16 => u16::from_le_bytes([buffer[0], buffer[1]]) as f64,
            Primitive::I32 => i32::from_le_bytes(buffer[..4].try_into().expect("4")) as f64,
            Primitive::U32 => u32::from_le_bytes(buffer[..4].try_into().expect("4")) as f64,
            Primitive::F32 => f32::from_le_bytes(buffer[..4].try_into().expect("4")) as f64,
            Primitive::I64 => i64::from_le_bytes(buffer) as f64,
            Primitive::U64 => u64::from_le_bytes(buffer) as f64,
            Primitive::F64 => f64::from_le_bytes(buffer),
        })
    }
}

/// Writes a message in little-endian CDR, field by field in its definition's order.
#[derive(Debug, Clone)]
pub struct Encoder {
    bytes: Vec<u8>,
}

impl Default for Encoder {
    fn default() -> Self {
        Encoder {
            bytes: vec![0, 1, 0, 0],
        }
    }
}

impl Encoder {
    fn align(&mut self, size: usize) {
        while !(self.bytes.len() - 4).is_multiple_of(size) {
            self.bytes.push(0);
        }
    }

    pub fn u8(&mut self, value: u8) -> &mut Self {
        self.bytes.push(value);
        self
    }

    pub fn u16(&mut self, value: u16) -> &mut Self {
        self.align(2);
        self.bytes.extend_from_slice(&value.to_le_bytes());
        self
    }

    pub fn i32(&mut self, value: i32) -> &mut Self {
        self.align(4);
        self.bytes.extend_from_slice(&value.to_le_bytes());
        self
    }

    pub fn u32(&mut self, value: u32) -> &mut Self {
        self.align(4);
        self.bytes.extend_from_slice(&value.to_le_bytes());
        self
    }

    pub fn f32(&mut self, value: f32) -> &mut Self {
        self.align(4);
        self.bytes.extend_from_slice(&value.to_le_bytes());
        self
    }

    pub fn f64(&mut self, value: f64) -> &mut Self {
        self.align(8);
        self.bytes.extend_from_slice(&value.to_le_bytes());
        self
    }

    pub fn f64s(&mut self, values: &[f64]) -> &mut Self {
        for &value in values {
            self.f64(value);
        }
        self
    }

    pub fn text(&mut self, text: &str) -> &mut Self {
        self.u32(text.len() as u32 + 1);
        self.bytes.extend_from_slice(text.as_bytes());
        self.bytes.push(0);
        self
    }

    /// A `std_msgs/Header`: the stamp in nanoseconds, and the frame.
    pub fn header(&mut self, stamp_ns: i64, frame_id: &str) -> &mut Self {
        self.i32(stamp_ns.div_euclid(1_000_000_000) as i32)
            .u32(stamp_ns.rem_euclid(1_000_000_000) as u32)
            .text(frame_id)
    }

    pub fn finish(&mut self) -> Vec<u8> {
        std::mem::take(&mut self.bytes)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A message written by the encoder reads back field by field, aligned as CDR
    /// aligns it; big-endian bytes read too; a short message is refused at its byte.
    #[test]
    fn a_message_reads_back_as_written_and_a_short_one_is_refused() {
        let definitions = Definitions::carried();
        let mut encoder = Encoder::default();
        encoder
            .header(1_700_000_000_250_000_000, "dvl_link")
            .u8(1)
            .u8(0);
        encoder.f64s(&[0.5, -0.25, 0.125]).f64s(&[0.01; 9]);
        encoder
            .f64s(&[12.0, 0.0, 0.0])
            .u8(4)
            .f32(1500.0)
            .u8(1)
            .u8(1);
        for _ in 0..4 {
            encoder.f64s(&[0.0, 0.0, 1.0]);
        }
        encoder.f64s(&[10.0; 4]);
        for _ in 0..16 {
            encoder.f32(0.0);
        }
        let bytes = encoder.finish();
        let value = decode(&bytes, "marine_acoustic_msgs/msg/Dvl", &definitions).unwrap();
        let path = |p: &str| {
            definitions
                .path("marine_acoustic_msgs/msg/Dvl", p)
                .unwrap()
                .0
        };
        let number = |p: &str| value.at(&path(p)).unwrap().number().unwrap();
        assert_eq!(number("header.stamp.sec"), 1_700_000_000.0);
        assert_eq!(number("header.stamp.nanosec"), 250_000_000.0);
        assert_eq!(
            value.at(&path("header.frame_id")).unwrap().text(),
            Some("dvl_link")
        );
        assert_eq!(number("velocity.y"), -0.25);
        assert_eq!(number("num_good_beams"), 4.0);
        assert_eq!(number("sound_speed"), 1500.0);
        assert_eq!(number("beam_velocities_valid"), 1.0);
        // Big-endian: the same fields, each reversed.
        let mut big = vec![0, 0, 0, 0];
        big.extend_from_slice(&7i32.to_be_bytes());
        big.extend_from_slice(&9u32.to_be_bytes());
        big.extend_from_slice(&1u32.to_be_bytes());
        big.push(0);
        let time = decode(&big[..12], "builtin_interfaces/msg/Time", &definitions).unwrap();
        assert_eq!(
            time,
            Value::List(vec![Value::Number(7.0), Value::Number(9.0)])
        );
        let header = decode(&big, "std_msgs/msg/Header", &definitions).unwrap();
        assert_eq!(header.at(&[1]).unwrap().text(), Some(""));
        let error = decode(&bytes[..40], "marine_acoustic_msgs/msg/Dvl", &definitions).unwrap_err();
        assert_eq!(
            error.to_string(),
            "the message ends at byte 40 where geometry_msgs/msg/Vector3.y needs 4 more"
        );
        // A type that holds itself is refused, not followed until the stack runs out;
        // a sequence longer than what is left of the message, likewise.
        // Its definition is refused where it is read, naming the field; decoding
        // does not rely on that.
        let mut looped = Definitions::default();
        let error = looped.add("a/Loop", "a/Loop inner\n").unwrap_err();
        assert_eq!(
            error.to_string(),
            "the definition of a/msg/Loop, line 1: field inner is of type a/msg/Loop itself: a type that holds itself has no end, and no ROS message is one"
        );
        let mut again = Definitions::default();
        again
            .add("a/Pair", "a/Other first\n===\nMSG: a/Other\na/Pair back\n")
            .unwrap_err();
        looped.types.insert(
            "a/msg/Loop".into(),
            vec![Field {
                name: "inner".into(),
                element: Element::Message("a/msg/Loop".into()),
                count: Count::One,
            }],
        );
        let error = decode(&[0, 1, 0, 0], "a/Loop", &looped).unwrap_err();
        assert!(matches!(error, CdrError::Nested(_)), "{error}");
        let long = [0, 1, 0, 0, 255, 255, 255, 0];
        let error = decode(&long, "tf2_msgs/msg/TFMessage", &definitions).unwrap_err();
        assert!(matches!(error, CdrError::Length { .. }), "{error}");
        let error = decode(&[0, 3, 0, 0], "std_msgs/msg/Header", &definitions).unwrap_err();
        assert!(error.to_string().contains("0x0003"), "{error}");
    }
}
