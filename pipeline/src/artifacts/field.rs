//! Where in an artifact a problem is: a path of keys and indices, built as
//! the checks descend and written out only for an error.

use std::fmt;

#[derive(Debug, Clone, Copy)]
enum Segment<'a> {
    Root,
    Key(&'a str),
    Index(usize),
}

/// A JSON-path-like location (`demonstrations[3].start[1].at`): a chain
/// of segments borrowed from the caller's stack, so descending costs no
/// allocation.
#[derive(Debug, Clone, Copy)]
pub struct Field<'a> {
    parent: Option<&'a Field<'a>>,
    segment: Segment<'a>,
}

impl Field<'static> {
    /// The whole file (written as nothing).
    pub const ROOT: Field<'static> = Field {
        parent: None,
        segment: Segment::Root,
    };
}

impl<'a> Field<'a> {
    /// The member `key` of this object.
    pub fn key<'b>(&'b self, key: &'b str) -> Field<'b> {
        Field {
            parent: Some(self),
            segment: Segment::Key(key),
        }
    }

    /// The element `index` of this array.
    pub fn index(&self, index: usize) -> Field<'_> {
        Field {
            parent: Some(self),
            segment: Segment::Index(index),
        }
    }
}

impl fmt::Display for Field<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let mut segments = Vec::new();
        let mut at = Some(self);
        while let Some(field) = at {
            segments.push(field.segment);
            at = field.parent;
        }
        let mut first = true;
        for segment in segments.iter().rev() {
            match segment {
                Segment::Root => continue,
                Segment::Key(k) if first => write!(f, "{k}")?,
                Segment::Key(k) => write!(f, ".{k}")?,
                Segment::Index(i) => write!(f, "[{i}]")?,
            }
            first = false;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::Field;

    #[test]
    fn paths_are_written_like_json_paths() {
        let root = Field::ROOT;
        assert_eq!(root.to_string(), "");
        let demos = root.key("demonstrations");
        let d = demos.index(3);
        let start = d.key("start");
        let s = start.index(1);
        assert_eq!(s.key("at").to_string(), "demonstrations[3].start[1].at");
        assert_eq!(
            root.key("edge_index").index(0).index(2).to_string(),
            "edge_index[0][2]"
        );
    }
}
