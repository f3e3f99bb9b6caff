//! "Did you mean" suggestions by edit distance.

/// Edit distance between two short words, by characters: insertions,
/// deletions, substitutions and swaps of two neighbours (`slto` for
/// `slot`) each count one (the optimal string alignment distance).
pub fn edit_distance(a: &str, b: &str) -> usize {
    let a: Vec<char> = a.chars().collect();
    let b: Vec<char> = b.chars().collect();
    // Rows i - 2, i - 1 and i of the distance table.
    let mut before: Vec<usize> = Vec::new();
    let mut above: Vec<usize> = (0..=b.len()).collect();
    for i in 1..=a.len() {
        let mut row = vec![i; b.len() + 1];
        for j in 1..=b.len() {
            let cost = usize::from(a[i - 1] != b[j - 1]);
            row[j] = (above[j] + 1).min(row[j - 1] + 1).min(above[j - 1] + cost);
            if i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1] {
                row[j] = row[j].min(before[j - 2] + 1);
            }
        }
        before = std::mem::replace(&mut above, row);
    }
    above[b.len()]
}

/// The candidate closest to `word`, if it is close enough to be a likely
/// typo (at most a third of the word's length, at least one edit, ignoring
/// case), ties broken by the candidates' order.
pub fn closest<'a, I>(word: &str, candidates: I) -> Option<&'a str>
where
    I: IntoIterator<Item = &'a str>,
{
    // A name of one or two characters is within one edit of every other
    // such name (`D` for `A`): only another case of it is suggested.
    let len = word.chars().count();
    let limit = if len < 3 { 0 } else { (len / 3).max(1) };
    let lower = word.to_lowercase();
    candidates
        .into_iter()
        .filter(|c| *c != word)
        .map(|c| (edit_distance(&lower, &c.to_lowercase()), c))
        .filter(|(d, _)| *d <= limit)
        .min_by_key(|(d, _)| *d)
        .map(|(_, c)| c)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// One- and two-character names get no suggestion from another name
    /// one edit away (a helper's `D -> g2` was told "did you mean `A`?",
    /// A already in the order), only another case of themselves.
    #[test]
    fn short_names_are_not_matched_to_any_other_short_name() {
        assert_eq!(closest("D", ["A", "B", "C"]), None);
        assert_eq!(closest("d", ["A", "D"]), Some("D"));
        assert_eq!(closest("g3", ["g1", "g2"]), None);
        assert_eq!(closest("slto", ["slot", "s1"]), Some("slot"));
    }

    #[test]
    fn distances() {
        assert_eq!(edit_distance("stock5", "stok5"), 1);
        assert_eq!(edit_distance("", "abc"), 3);
        assert_eq!(edit_distance("order", "ordr"), 1);
        assert_eq!(edit_distance("kitten", "sitting"), 3);
        assert_eq!(edit_distance("slto", "slot"), 1);
        assert_eq!(edit_distance("prodcut", "product"), 1);
        assert_eq!(edit_distance("ab", "ba"), 1);
        assert_eq!(edit_distance("abc", ""), 3);
    }

    #[test]
    fn suggestions() {
        let names = ["stock3", "stock5", "bench"];
        assert_eq!(closest("stok5", names), Some("stock5"));
        assert_eq!(closest("Bench", names), Some("bench"));
        assert_eq!(closest("tray", names), None);
        assert_eq!(closest("g6", ["g1", "g2"]), None);
        assert_eq!(closest("slto", ["box", "slot", "lift"]), Some("slot"));
    }
}
