//! A bound on XML element nesting, checked before the URDF parser sees the
//! text: the parser builds and prints its element tree recursively, so a
//! deeply nested file (100 000 levels) would overflow the stack and abort the
//! process. This scan is iterative and allocates nothing.

/// Deepest element nesting a URDF may have. A URDF needs 5 levels
/// (`robot/link/collision/geometry/box`); vendor extensions (`<gazebo>`,
/// `<transmission>`) a few more.
pub const MAX_XML_DEPTH: usize = 64;

/// The first nesting level above `max` reached by `text`'s elements, if any
/// (`Err(level)`). Comments, CDATA, processing instructions and declarations
/// are skipped; `>` inside quoted attribute values does not end a tag.
/// Malformed text is left to the parser (it refuses it with a message).
pub(crate) fn check_depth(text: &str, max: usize) -> Result<(), usize> {
    let b = text.as_bytes();
    let mut depth = 0usize;
    let mut i = 0usize;
    while let Some(off) = find(b, i, b"<") {
        i = off + 1;
        let rest = &b[i..];
        if rest.starts_with(b"!--") {
            i = find(b, i + 3, b"-->").map_or(b.len(), |e| e + 3);
        } else if rest.starts_with(b"![CDATA[") {
            i = find(b, i + 8, b"]]>").map_or(b.len(), |e| e + 3);
        } else if rest.starts_with(b"?") {
            i = find(b, i + 1, b"?>").map_or(b.len(), |e| e + 2);
        } else if rest.starts_with(b"!") {
            i = skip_declaration(b, i + 1);
        } else if rest.starts_with(b"/") {
            depth = depth.saturating_sub(1);
            i = find(b, i, b">").map_or(b.len(), |e| e + 1);
        } else {
            let (end, self_closing) = end_of_tag(b, i);
            i = end;
            if !self_closing {
                depth += 1;
                if depth > max {
                    return Err(depth);
                }
            }
        }
    }
    Ok(())
}

/// Index of the first `pat` in `b` at or after `from`.
fn find(b: &[u8], from: usize, pat: &[u8]) -> Option<usize> {
    b.get(from..)?
        .windows(pat.len())
        .position(|w| w == pat)
        .map(|p| p + from)
}

/// Past the `>` of a start tag beginning at `from` (after its `<`), quotes
/// respected; whether it was `/>`.
fn end_of_tag(b: &[u8], from: usize) -> (usize, bool) {
    let mut quote: Option<u8> = None;
    let mut prev = 0u8;
    for (k, &c) in b.iter().enumerate().skip(from) {
        match quote {
            Some(q) if c == q => quote = None,
            Some(_) => {}
            None if c == b'"' || c == b'\'' => quote = Some(c),
            None if c == b'>' => return (k + 1, prev == b'/'),
            None => {}
        }
        prev = c;
    }
    (b.len(), false)
}

/// Past a `<!…>` declaration (e.g. `<!DOCTYPE … [ … ]>`), brackets and quotes respected.
fn skip_declaration(b: &[u8], from: usize) -> usize {
    let mut quote: Option<u8> = None;
    let mut brackets = 0usize;
    for (k, &c) in b.iter().enumerate().skip(from) {
        match quote {
            Some(q) if c == q => quote = None,
            Some(_) => {}
            None => match c {
                b'"' | b'\'' => quote = Some(c),
                b'[' => brackets += 1,
                b']' => brackets = brackets.saturating_sub(1),
                b'>' if brackets == 0 => return k + 1,
                _ => {}
            },
        }
    }
    b.len()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_elements_not_comments_quotes_or_self_closing_tags() {
        let ok = "<?xml version=\"1.0\"?><!-- <a><b><c> --><!DOCTYPE r [<!ENTITY x \"<y>\">]><r a=\"<q>\"><l b='>'/><![CDATA[<z><z>]]><m></m></r>";
        assert_eq!(check_depth(ok, 2), Ok(()));
        assert_eq!(check_depth(ok, 1), Err(2));
        let deep = "<a>".repeat(100_000);
        assert_eq!(check_depth(&deep, MAX_XML_DEPTH), Err(MAX_XML_DEPTH + 1));
        let closed = "<a></a>".repeat(100_000);
        assert_eq!(check_depth(&closed, 1), Ok(()));
        assert_eq!(check_depth("", 0), Ok(()));
        assert_eq!(check_depth("<a", 0), Err(1));
        assert_eq!(
            check_depth("<a/", 0),
            Err(1),
            "malformed: left to the parser"
        );
    }
}
