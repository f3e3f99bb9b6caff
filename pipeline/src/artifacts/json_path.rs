//! The field a JSON parse error is in: serde_json says where it stopped
//! (line and byte column), not in which field; a scan of the text up to
//! there finds the enclosing keys and indices.

/// One open object or array before the error.
enum Frame {
    /// The key whose value is being read (`None` between members).
    Object(Option<String>),
    /// The element being read.
    Array(usize),
}

/// The field (`cells[0].slots[2].label`) at `line` (1-based) and `column`
/// (serde_json's: the bytes of that line read before the error) of
/// `bytes`. The scan stops where the parser did, so a value's error names
/// the value, and a missing field (reported once the object's `}` is read)
/// names the object. Empty at the top level or when the position is
/// outside the text.
pub fn at(bytes: &[u8], line: usize, column: usize) -> String {
    let mut start = 0;
    for _ in 1..line {
        match bytes[start..].iter().position(|&b| b == b'\n') {
            Some(n) => start += n + 1,
            None => return String::new(),
        }
    }
    let end = (start + column).min(bytes.len());
    let mut stack: Vec<Frame> = Vec::new();
    let mut string: Option<Vec<u8>> = None;
    let mut is_key = false;
    let mut escaped = false;
    for &b in &bytes[..end] {
        if let Some(text) = string.as_mut() {
            if escaped {
                escaped = false;
                text.push(b);
            } else if b == b'\\' {
                escaped = true;
            } else if b == b'"' {
                if is_key && let Some(Frame::Object(key)) = stack.last_mut() {
                    *key = Some(String::from_utf8_lossy(text).into_owned());
                }
                string = None;
            } else {
                text.push(b);
            }
            continue;
        }
        match b {
            b'"' => {
                is_key = matches!(stack.last(), Some(Frame::Object(None)));
                string = Some(Vec::new());
            }
            b'{' => stack.push(Frame::Object(None)),
            b'[' => stack.push(Frame::Array(0)),
            b'}' | b']' => {
                stack.pop();
            }
            b',' => match stack.last_mut() {
                Some(Frame::Object(key)) => *key = None,
                Some(Frame::Array(i)) => *i += 1,
                None => {}
            },
            _ => {}
        }
    }
    let mut path = String::new();
    for frame in &stack {
        match frame {
            Frame::Object(Some(key)) if path.is_empty() => path.push_str(key),
            Frame::Object(Some(key)) => {
                path.push('.');
                path.push_str(key);
            }
            Frame::Object(None) => break,
            Frame::Array(i) => path.push_str(&format!("[{i}]")),
        }
    }
    path
}

#[cfg(test)]
mod tests {
    use serde::Deserialize;

    #[derive(Debug, Deserialize)]
    #[allow(dead_code)]
    struct Slot {
        label: u32,
        at: [f64; 2],
    }

    #[derive(Debug, Deserialize)]
    #[allow(dead_code)]
    struct File {
        name: String,
        slots: Vec<Slot>,
    }

    /// The field serde_json's error in `text` is in.
    fn field_of(text: &str) -> String {
        match serde_json::from_str::<File>(text) {
            Ok(f) => panic!("parsed: {f:?}"),
            Err(e) => super::at(text.as_bytes(), e.line(), e.column()),
        }
    }

    #[test]
    fn parse_errors_are_placed_in_their_field() {
        let pretty = "{\n  \"name\": \"a\",\n  \"slots\": [\n    {\"label\": 1, \"at\": [0.0, 0.1]},\n    {\n      \"label\": -1,\n      \"at\": [0.0, 0.1]\n    }\n  ]\n}\n";
        assert_eq!(field_of(pretty), "slots[1].label");
        let text = r#"{"name": "a", "slots": [{"label": 1, "at": [0.0, 1e999]}]}"#;
        assert_eq!(field_of(text), "slots[0].at[1]");
        let text = r#"{"name": "a", "slots": [{"label": 1, "at": [NaN, 0.0]}]}"#;
        assert_eq!(field_of(text), "slots[0].at[0]");
        let text = r#"{"name": "a", "slots": [{"label": 1, "at": [null, 0.0]}]}"#;
        assert_eq!(field_of(text), "slots[0].at[0]");
        let text = r#"{"name": "a\"b", "slots": [{"label": 1}]}"#;
        assert_eq!(field_of(text), "slots[0]");
        let text = r#"{"name": 3, "slots": []}"#;
        assert_eq!(field_of(text), "name");
        assert_eq!(field_of(r#"{"name": "a"}"#), "");
        assert_eq!(field_of(""), "");
    }
}
