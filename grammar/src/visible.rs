//! Characters a terminal does not show (control characters, zero-width
//! and bidirectional marks, spaces other than the ASCII one), named so
//! that a diagnostic about one says what it is.

/// Whether `c` shows as nothing, or as a plain space, in a terminal: a
/// control character other than a tab, a format character (zero-width
/// space, joiners, bidirectional marks, a byte order mark) or a space
/// other than U+0020.
pub fn is_invisible(c: char) -> bool {
    (c.is_control() && c != '\t' && c != '\n' && c != '\r')
        || matches!(
            c,
            '\u{00A0}'
                | '\u{00AD}'
                | '\u{034F}'
                | '\u{061C}'
                | '\u{115F}'
                | '\u{1160}'
                | '\u{17B4}'
                | '\u{17B5}'
                | '\u{180E}'
                | '\u{2000}'..='\u{200F}'
                | '\u{2028}'..='\u{202F}'
                | '\u{205F}'..='\u{206F}'
                | '\u{3000}'
                | '\u{3164}'
                | '\u{FEFF}'
                | '\u{FFA0}'
                | '\u{FFF9}'..='\u{FFFB}'
        )
}

/// `c` as a diagnostic shows it in a source line: one visible character
/// in its place (a control character as its Unicode control picture, any
/// other invisible one as `␣`), so that the carets still line up.
pub fn shown(c: char) -> char {
    match c {
        c if !is_invisible(c) => c,
        '\u{0}'..='\u{1F}' => char::from_u32(0x2400 + c as u32).unwrap_or('␣'),
        '\u{7F}' => '␡',
        _ => '␣',
    }
}

/// `c` named for a message: itself in backticks, or, when invisible, its
/// code point (`U+200B`, a zero-width space, shows as nothing).
pub fn named(c: char) -> String {
    if is_invisible(c) {
        format!("the invisible character U+{:04X}", c as u32)
    } else {
        format!("`{c}`")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn invisible_characters_are_named_and_shown_in_their_place() {
        for c in [
            '\0', '\u{200B}', '\u{202E}', '\u{00A0}', '\u{FEFF}', '\u{7F}',
        ] {
            assert!(is_invisible(c), "{c:?}");
            assert!(!is_invisible(shown(c)), "{c:?} shown as {:?}", shown(c));
        }
        for c in ['a', ' ', '\t', 'é', '中', '→'] {
            assert!(!is_invisible(c), "{c:?}");
            assert_eq!(shown(c), c);
        }
        assert_eq!(shown('\0'), '␀');
        assert_eq!(named('\u{200B}'), "the invisible character U+200B");
        assert_eq!(named('x'), "`x`");
    }
}
