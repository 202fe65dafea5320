//! The keys of two specs whose values differ. In: two resolved specs as TOML tables.
//! Out: each differing key in `--set`'s dotted form with its value on either side.

/// A spec key whose value differs; `None` where a side lacks the key.
#[derive(Debug, Clone, PartialEq)]
pub struct KeyDifference {
    pub key: String,
    pub a: Option<String>,
    pub b: Option<String>,
}

/// The spec as `dotted.key = value` pairs in file order: tables open into dotted keys,
/// arrays of tables into `key[i]` as `--set` writes them (`dvl[1].noise_cm_s`), and any
/// other value, arrays of numbers included, stays whole as TOML text.
pub fn flatten(table: &toml::Table) -> Vec<(String, String)> {
    let mut pairs = Vec::new();
    for (key, value) in table {
        flatten_into(key.clone(), value, &mut pairs);
    }
    pairs
}

fn flatten_into(key: String, value: &toml::Value, pairs: &mut Vec<(String, String)>) {
    match value {
        toml::Value::Table(table) => {
            for (name, value) in table {
                flatten_into(format!("{key}.{name}"), value, pairs);
            }
        }
        toml::Value::Array(items) if !items.is_empty() && items.iter().all(|i| i.is_table()) => {
            for (index, item) in items.iter().enumerate() {
                flatten_into(format!("{key}[{index}]"), item, pairs);
            }
        }
        other => pairs.push((key, other.to_string())),
    }
}

/// The keys whose values differ, A's order first, then the keys only B has.
pub fn spec_differences(a: &toml::Table, b: &toml::Table) -> Vec<KeyDifference> {
    let (a, b) = (flatten(a), flatten(b));
    let find = |pairs: &[(String, String)], key: &str| {
        pairs.iter().find(|(k, _)| k == key).map(|(_, v)| v.clone())
    };
    let mut differences: Vec<KeyDifference> = a
        .iter()
        .filter_map(|(key, value)| {
            let other = find(&b, key);
            (other.as_ref() != Some(value)).then(|| KeyDifference {
                key: key.clone(),
                a: Some(value.clone()),
                b: other,
            })
        })
        .collect();
    differences.extend(
        b.iter()
            .filter(|(key, _)| find(&a, key).is_none())
            .map(|(key, value)| KeyDifference {
                key: key.clone(),
                a: None,
                b: Some(value.clone()),
            }),
    );
    differences
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn specs_flatten_to_set_keys_and_differ_key_by_key() {
        let a: toml::Table = toml::from_str(
            "name = \"quick\"\n[calibration]\nwindow_sizes_s = [20.0, 40.0]\nmonte_carlo_runs = 3\n[[dvl]]\nname = \"DVL1\"\nnoise_cm_s = 2.0\n[[dvl]]\nname = \"DVL2\"\nnoise_cm_s = 0.02\n",
        )
        .unwrap();
        assert_eq!(
            flatten(&a)
                .iter()
                .map(|(k, v)| format!("{k} = {v}"))
                .collect::<Vec<_>>(),
            [
                "name = \"quick\"",
                "calibration.window_sizes_s = [20.0, 40.0]",
                "calibration.monte_carlo_runs = 3",
                "dvl[0].name = \"DVL1\"",
                "dvl[0].noise_cm_s = 2.0",
                "dvl[1].name = \"DVL2\"",
                "dvl[1].noise_cm_s = 0.02",
            ]
        );
        let b: toml::Table = toml::from_str(
            "name = \"quick\"\nseed = 1\n[calibration]\nwindow_sizes_s = [20.0, 60.0]\n[[dvl]]\nname = \"DVL1\"\nnoise_cm_s = 2.0\n[[dvl]]\nname = \"DVL2\"\nnoise_cm_s = 0.05\n",
        )
        .unwrap();
        let text = |value: &str| Some(value.to_string());
        assert_eq!(
            spec_differences(&a, &b),
            vec![
                KeyDifference {
                    key: "calibration.window_sizes_s".into(),
                    a: text("[20.0, 40.0]"),
                    b: text("[20.0, 60.0]"),
                },
                KeyDifference {
                    key: "calibration.monte_carlo_runs".into(),
                    a: text("3"),
                    b: None,
                },
                KeyDifference {
                    key: "dvl[1].noise_cm_s".into(),
                    a: text("0.02"),
                    b: text("0.05"),
                },
                KeyDifference {
                    key: "seed".into(),
                    a: None,
                    b: text("1"),
                },
            ]
        );
        assert!(spec_differences(&a, &a).is_empty());
    }
}
