//! Facts about a model file's raw text that the XML parser does not give cheaply: the line of a byte
//! offset (for messages), and how deeply elements nest (checked before parsing).
//!
//! `roxmltree` computes a line by rescanning the text from its start, which made loading quadratic in
//! the file size when every element's line was kept; [`LineIndex`] answers in O(log lines). Its parser
//! descends recursively into nested elements, so a file nesting elements tens of thousands deep
//! overflows the stack (an abort, not an error), and it compares each attribute's name with those before
//! it on its element, so an element with 200,000 attributes took a minute to parse (quadratic);
//! [`beyond_limits`] finds such a file first.

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

/// The most attributes one element may have. URDF elements have up to about six; the limit leaves
/// ample room for any real file while the parser's duplicate check, quadratic in the attributes of one
/// element, stays under a millisecond.
pub(crate) const MAX_ATTRIBUTES: usize = 1000;

/// Markup beyond what a model file needs, found before parsing.
#[derive(Debug, PartialEq, Eq)]
pub(crate) enum Beyond {
    /// An element opened deeper than the nesting limit: the byte offset of its `<` and its depth.
    Nesting { offset: usize, depth: usize },
    /// An element with more attributes than the limit: the byte offset of its `<` and how many it has
    /// (counted up to one past the limit).
    Attributes { offset: usize, count: usize },
}

/// Finds the first element nested deeper than `nesting` (the root element has depth 1) or with more
/// than `attributes` attributes.
///
/// A linear scan of the markup that skips what can hold a `<` or `>` without opening an element:
/// comments, CDATA sections, processing instructions, a `<!DOCTYPE …>` (with its internal subset) and
/// quoted attribute values; a self-closing tag opens nothing; an attribute is an `=` outside quotes. It
/// only counts: on malformed text it stops or miscounts harmlessly and the XML parser then reports the
/// error. Entities cannot add nesting, because the parser is run without DTD support and so no entity
/// can expand to markup.
pub(crate) fn beyond_limits(text: &str, nesting: usize, attributes: usize) -> Option<Beyond> {
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
            let tag = end_of_start_tag(bytes, p + 1)?;
            if tag.attributes > attributes {
                return Some(Beyond::Attributes {
                    offset: p,
                    count: tag.attributes,
                });
            }
            if !tag.self_closing {
                depth += 1;
                if depth > nesting {
                    return Some(Beyond::Nesting { offset: p, depth });
                }
            }
            tag.end
        };
    }
    None
}

/// A start tag as [`end_of_start_tag`] reads it.
struct StartTag {
    /// One past its `>`.
    end: usize,
    /// Whether it ends with `/>`.
    self_closing: bool,
    /// Its `=` outside quoted values: its attributes, on well-formed text.
    attributes: usize,
}

/// The start tag whose name begins at `from`. Attribute values are quoted with `"` or `'` and may
/// contain `>`, `/` and `=`.
fn end_of_start_tag(bytes: &[u8], from: usize) -> Option<StartTag> {
    let mut i = from;
    let mut attributes = 0usize;
    while i < bytes.len() {
        match bytes[i] {
            q @ (b'"' | b'\'') => {
                i += 1 + bytes[i + 1..].iter().position(|&b| b == q)?;
            }
            b'=' => attributes += 1,
            b'>' => {
                return Some(StartTag {
                    end: i + 1,
                    self_closing: i > from && bytes[i - 1] == b'/',
                    attributes,
                })
            }
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

    /// The depth of the first element nested deeper than `limit`, with no limit on attributes.
    fn too_deep(text: &str, limit: usize) -> Option<usize> {
        match beyond_limits(text, limit, usize::MAX) {
            Some(Beyond::Nesting { depth, .. }) => Some(depth),
            _ => None,
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
        assert_eq!(too_deep(&nested(10, ""), 10), None);
        let text = nested(11, "");
        assert_eq!(
            beyond_limits(&text, 10, MAX_ATTRIBUTES),
            Some(Beyond::Nesting {
                offset: "<robot>".len() + 9 * "<a>".len(),
                depth: 11
            })
        );
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
            assert_eq!(too_deep(&text, 2), None, "{inner}");
        }
        let doctype = "<!DOCTYPE robot [ <!ENTITY e \"<x>\"> <!-- ] > --> ]><robot><a/></robot>";
        assert_eq!(too_deep(doctype, 1), None);
        // A quoted `>` does not end a start tag early, nor does a quoted `/` make it self-closing.
        let text = "<robot><a v=\">\"><b></b></a></robot>";
        assert_eq!(too_deep(text, 2), Some(3));
        let text = "<robot><a><b v=\"/\"></b></a></robot>";
        assert_eq!(too_deep(text, 2), Some(3));
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
            assert_eq!(beyond_limits(text, 0, 0), None, "{text}");
        }
    }

    #[test]
    fn attributes_beyond_the_limit_are_found_and_quoted_equals_are_not_counted() {
        let element = |n: usize| {
            let attributes: String = (0..n).map(|k| format!(" a{k}=\"x=y\"")).collect();
            format!("<robot><link{attributes}/></robot>")
        };
        assert_eq!(beyond_limits(&element(3), 256, 3), None);
        assert_eq!(
            beyond_limits(&element(4), 256, 3),
            Some(Beyond::Attributes {
                offset: "<robot>".len(),
                count: 4
            })
        );
        // The attacker's file: 200,000 attributes on one element took roxmltree a minute to parse.
        let text = element(200_000);
        let started = std::time::Instant::now();
        assert!(matches!(
            beyond_limits(&text, MAX_NESTING, MAX_ATTRIBUTES),
            Some(Beyond::Attributes { count: 200_000, .. })
        ));
        eprintln!("scan of {} bytes: {:?}", text.len(), started.elapsed());
    }
}
