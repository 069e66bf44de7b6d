//! Facts about a model file's raw text that the XML parser does not give cheaply: the line of a byte
//! offset (for messages), and how deeply elements nest (checked before parsing).
//!
//! `roxmltree` computes a line by rescanning the text from its start, which made loading quadratic in
//! the file size when every element's line was kept; [`LineIndex`] answers in O(log lines). Its parser
//! descends recursively into nested elements, so a file nesting elements tens of thousands deep
//! overflows the stack (an abort, not an error); [`nesting_too_deep`] finds such a file first.

/// Byte offset → 1-based line, from the offsets where lines start (built once per file).
pub(crate) struct LineIndex {
    /// Byte offset of the first character of each line; `line_starts[0] == 0`.
    line_starts: Vec<usize>,
}

impl LineIndex {
    pub(crate) fn new(text: &str) -> Self {
        let mut line_starts = vec![0];
        line_starts.extend(
            text.bytes()
                .enumerate()
                .filter(|&(_, b)| b == b'\n')
                .map(|(i, _)| i + 1),
        );
        LineIndex { line_starts }
    }

    /// The line holding byte `offset` (lines end at `\n`, as `roxmltree` counts them).
    pub(crate) fn line(&self, offset: usize) -> u32 {
        let line = self.line_starts.partition_point(|&start| start <= offset);
        u32::try_from(line).unwrap_or(u32::MAX)
    }
}

/// The deepest nesting of elements a model file may have. URDF needs about six levels
/// (`robot/link/visual/geometry/mesh`, xacro leftovers a few more); the limit leaves ample room for
/// any real file while keeping the parser's recursion far from the stack's end, even on a test
/// thread's 2 MiB stack.
pub(crate) const MAX_NESTING: usize = 256;

/// An element opened deeper than [`MAX_NESTING`]: the byte offset of its `<` and its depth.
#[derive(Debug, PartialEq, Eq)]
pub(crate) struct TooDeep {
    pub offset: usize,
    pub depth: usize,
}

/// Finds the first element nested deeper than `limit` (the root element has depth 1).
///
/// A linear scan of the markup that skips what can hold a `<` or `>` without opening an element:
/// comments, CDATA sections, processing instructions, a `<!DOCTYPE …>` (with its internal subset) and
/// quoted attribute values; a self-closing tag opens nothing. It only counts: on malformed text it
/// stops or miscounts harmlessly and the XML parser then reports the error. Entities cannot add
/// nesting, because the parser is run without DTD support and so no entity can expand to markup.
pub(crate) fn nesting_too_deep(text: &str, limit: usize) -> Option<TooDeep> {
    let bytes = text.as_bytes();
    let find = |from: usize, pattern: &[u8]| -> Option<usize> {
        bytes
            .get(from..)?
            .windows(pattern.len())
            .position(|w| w == pattern)
            .map(|p| from + p)
    };
    let mut depth = 0usize;
    let mut i = 0;
    while let Some(p) = find(i, b"<") {
        let rest = &bytes[p..];
        i = if rest.starts_with(b"<!--") {
            find(p + 4, b"-->")? + 3
        } else if rest.starts_with(b"<![CDATA[") {
            find(p + 9, b"]]>")? + 3
        } else if rest.starts_with(b"<?") {
            find(p + 2, b"?>")? + 2
        } else if rest.starts_with(b"<!") {
            end_of_declaration(bytes, p + 2)?
        } else if rest.starts_with(b"</") {
            depth = depth.saturating_sub(1);
            find(p + 2, b">")? + 1
        } else {
            let (end, self_closing) = end_of_start_tag(bytes, p + 1)?;
            if !self_closing {
                depth += 1;
                if depth > limit {
                    return Some(TooDeep { offset: p, depth });
                }
            }
            end
        };
    }
    None
}

/// One past the `>` closing a start tag whose name begins at `from`, and whether it is `/>`.
/// Attribute values are quoted with `"` or `'` and may contain `>` and `/`.
fn end_of_start_tag(bytes: &[u8], from: usize) -> Option<(usize, bool)> {
    let mut i = from;
    while i < bytes.len() {
        match bytes[i] {
            q @ (b'"' | b'\'') => {
                i += 1 + bytes[i + 1..].iter().position(|&b| b == q)?;
            }
            b'>' => return Some((i + 1, i > from && bytes[i - 1] == b'/')),
            _ => {}
        }
        i += 1;
    }
    None
}

/// One past the `>` closing a markup declaration (`<!DOCTYPE …>`), skipping quoted strings, comments
/// and the bracketed internal subset with the declarations inside it.
fn end_of_declaration(bytes: &[u8], from: usize) -> Option<usize> {
    let mut brackets = 0usize;
    let mut i = from;
    while i < bytes.len() {
        match bytes[i] {
            q @ (b'"' | b'\'') => {
                i += 1 + bytes[i + 1..].iter().position(|&b| b == q)?;
            }
            b'<' if bytes[i..].starts_with(b"<!--") => {
                i += 4 + bytes[i + 4..].windows(3).position(|w| w == b"-->")? + 2;
            }
            b'[' => brackets += 1,
            b']' => brackets = brackets.saturating_sub(1),
            b'>' if brackets == 0 => return Some(i + 1),
            _ => {}
        }
        i += 1;
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    fn naive_line(text: &str, offset: usize) -> u32 {
        1 + text[..offset].bytes().filter(|&b| b == b'\n').count() as u32
    }

    #[test]
    fn line_index_agrees_with_counting_newlines() {
        let text = "<robot>\n<link/>\r\n\n  <joint>\n</joint></robot>\n";
        let index = LineIndex::new(text);
        for offset in 0..=text.len() {
            assert_eq!(
                index.line(offset),
                naive_line(text, offset),
                "offset {offset}"
            );
        }
    }

    fn nested(depth: usize, inner: &str) -> String {
        format!(
            "<robot>{}{inner}{}</robot>",
            "<a>".repeat(depth - 1),
            "</a>".repeat(depth - 1)
        )
    }

    #[test]
    fn nesting_at_the_limit_passes_and_one_more_is_found() {
        assert_eq!(nesting_too_deep(&nested(10, ""), 10), None);
        let text = nested(11, "");
        let found = nesting_too_deep(&text, 10).unwrap();
        assert_eq!(found.depth, 11);
        assert_eq!(found.offset, "<robot>".len() + 9 * "<a>".len());
    }

    #[test]
    fn markup_that_opens_no_element_is_not_counted() {
        // Each of these holds `<x>` text that is not an element, at depth 2 under a limit of 2.
        for inner in [
            "<!-- <x><x><x> -->",
            "<![CDATA[<x><x><x>]]>",
            "<?pi <x><x><x> ?>",
            "<b v=\"<x>\" w='>/'/>",
            "<b/><b /><b\n/>",
        ] {
            let text = format!("<robot><a>{inner}</a></robot>");
            assert_eq!(nesting_too_deep(&text, 2), None, "{inner}");
        }
        let doctype = "<!DOCTYPE robot [ <!ENTITY e \"<x>\"> <!-- ] > --> ]><robot><a/></robot>";
        assert_eq!(nesting_too_deep(doctype, 1), None);
        // A quoted `>` does not end a start tag early, nor does a quoted `/` make it self-closing.
        let text = "<robot><a v=\">\"><b></b></a></robot>";
        assert_eq!(nesting_too_deep(text, 2).map(|t| t.depth), Some(3));
        let text = "<robot><a><b v=\"/\"></b></a></robot>";
        assert_eq!(nesting_too_deep(text, 2).map(|t| t.depth), Some(3));
    }

    #[test]
    fn malformed_text_ends_the_scan_without_panicking() {
        for text in [
            "<",
            "<!--",
            "<![CDATA[",
            "<?",
            "<!",
            "</",
            "<a v=\"",
            "<a",
            "<!D [",
            "<!D \"",
        ] {
            assert_eq!(nesting_too_deep(text, 0), None, "{text}");
        }
    }
}
