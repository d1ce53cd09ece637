//! A small element tree built from quick-xml's event reader, with the byte offset of every
//! element and of its text, so readers can report line and column for each field.

use quick_xml::events::Event;
use quick_xml::reader::Reader;

/// Elements nested deeper than this are refused (lens files need six levels).
const MAX_DEPTH: usize = 32;

/// One element: its name, where it starts, its text content and its child elements.
#[derive(Clone, Debug, Default)]
pub(crate) struct Node {
    pub name: String,
    /// Byte offset of the `<` of the start tag.
    pub pos: usize,
    /// Text content with entity references resolved (child elements' text excluded).
    pub text: String,
    /// Byte offset of the first non-whitespace character of the text, if any.
    pub text_pos: Option<usize>,
    pub children: Vec<Node>,
}

impl Node {
    /// Where a value in this element should be reported: its text, else the tag.
    pub fn value_pos(&self) -> usize {
        self.text_pos.unwrap_or(self.pos)
    }

    /// The text without surrounding whitespace.
    pub fn value(&self) -> &str {
        self.text.trim()
    }
}

/// The document is not well-formed XML.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(crate) struct XmlError {
    pub pos: usize,
    /// The innermost element open at the error, if any.
    pub element: Option<String>,
    pub message: String,
}

/// Parses `text` into its root element.
pub(crate) fn parse(text: &str) -> Result<Node, XmlError> {
    let mut reader = Reader::from_str(text);
    reader.config_mut().expand_empty_elements = true;
    let mut stack: Vec<Node> = Vec::new();
    let mut root: Option<Node> = None;
    let innermost = |stack: &[Node]| stack.last().map(|n| n.name.clone());
    loop {
        let pos = usize::try_from(reader.buffer_position()).unwrap_or(usize::MAX);
        let event = match reader.read_event() {
            Ok(e) => e,
            Err(e) => {
                return Err(XmlError {
                    pos: usize::try_from(reader.error_position()).unwrap_or(pos),
                    element: innermost(&stack),
                    message: format!("malformed XML: {e}"),
                });
            }
        };
        let end = usize::try_from(reader.buffer_position()).unwrap_or(usize::MAX);
        let fail = |stack: &[Node], message: String| XmlError {
            pos,
            element: innermost(stack),
            message,
        };
        match event {
            Event::Start(start) => {
                if root.is_some() {
                    return Err(fail(
                        &stack,
                        "a second root element after the end of the document".into(),
                    ));
                }
                if stack.len() >= MAX_DEPTH {
                    return Err(fail(
                        &stack,
                        format!("elements nested deeper than {MAX_DEPTH} levels"),
                    ));
                }
                stack.push(Node {
                    name: start.name().into_inner().to_string(),
                    pos,
                    ..Node::default()
                });
            }
            Event::End(_) => {
                let Some(node) = stack.pop() else {
                    return Err(fail(&stack, "an end tag without a start tag".into()));
                };
                match stack.last_mut() {
                    Some(parent) => parent.children.push(node),
                    None => root = Some(node),
                }
            }
            Event::Text(t) => {
                let raw = text.get(pos..end).unwrap_or("");
                let lead = raw.len() - raw.trim_start().len();
                let content = t.xml10_content();
                append_text(&mut stack, &content, pos + lead, !raw.trim().is_empty())
                    .map_err(|m| fail(&stack, m))?;
            }
            Event::CData(c) => {
                let content = c.xml10_content();
                append_text(&mut stack, &content, pos, !content.trim().is_empty())
                    .map_err(|m| fail(&stack, m))?;
            }
            Event::GeneralRef(r) => {
                let resolved = match r.resolve_char_ref() {
                    Ok(Some(c)) => c,
                    Ok(None) => match predefined_entity(&r) {
                        Some(c) => c,
                        None => {
                            return Err(fail(&stack, format!("unknown entity `&{};`", &*r)));
                        }
                    },
                    Err(e) => return Err(fail(&stack, format!("bad character reference: {e}"))),
                };
                let mut buf = [0u8; 4];
                let s: &str = resolved.encode_utf8(&mut buf);
                append_text(&mut stack, s, pos, !resolved.is_whitespace())
                    .map_err(|m| fail(&stack, m))?;
            }
            Event::Eof => {
                if let Some(open) = stack.last() {
                    return Err(XmlError {
                        pos: text.len(),
                        element: Some(open.name.clone()),
                        message: format!("unexpected end of file: <{}> is not closed", open.name),
                    });
                }
                return root.ok_or_else(|| XmlError {
                    pos: text.len(),
                    element: None,
                    message: "the file holds no XML element".into(),
                });
            }
            Event::Empty(_)
            | Event::Comment(_)
            | Event::Decl(_)
            | Event::PI(_)
            | Event::DocType(_) => {}
        }
    }
}

/// Adds text to the innermost open element; outside the root only whitespace is allowed.
fn append_text(
    stack: &mut [Node],
    content: &str,
    pos: usize,
    significant: bool,
) -> Result<(), String> {
    match stack.last_mut() {
        Some(node) => {
            if significant && node.text_pos.is_none() {
                node.text_pos = Some(pos);
            }
            node.text.push_str(content);
            Ok(())
        }
        None if significant => Err("text outside the root element".into()),
        None => Ok(()),
    }
}

fn predefined_entity(name: &str) -> Option<char> {
    Some(match name {
        "amp" => '&',
        "lt" => '<',
        "gt" => '>',
        "quot" => '"',
        "apos" => '\'',
        _ => return None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn builds_the_tree_with_positions_and_resolved_entities() {
        let text =
            "<?xml version=\"1.0\"?>\n<a>\n  <b> 1.5 </b>\n  <c>x &amp; y&#33;</c><d/>\n</a>\n";
        let root = parse(text).unwrap();
        assert_eq!(root.name, "a");
        assert_eq!(root.pos, text.find("<a>").unwrap());
        let b = &root.children[0];
        assert_eq!((b.name.as_str(), b.value()), ("b", "1.5"));
        assert_eq!(b.text_pos, Some(text.find("1.5").unwrap()));
        assert_eq!(root.children[1].text, "x & y!");
        assert_eq!(root.children[2].name, "d");
        assert_eq!(root.children[2].text_pos, None);
    }

    #[test]
    fn reports_truncation_and_mismatched_tags() {
        let e = parse("<a><b>1</b>").unwrap_err();
        assert_eq!(e.element.as_deref(), Some("a"));
        assert!(e.message.contains("not closed"), "{}", e.message);
        let e = parse("<a><b>1</c></a>").unwrap_err();
        assert_eq!(e.element.as_deref(), Some("b"));
        assert!(parse("<a/><b/>").is_err());
        assert!(parse("text").is_err());
        assert!(parse("").is_err());
        assert!(parse("<a>&bogus;</a>").is_err());
    }

    #[test]
    fn refuses_deep_nesting() {
        let deep = "<a>".repeat(100);
        let e = parse(&deep).unwrap_err();
        assert!(e.message.contains("nested"), "{}", e.message);
    }
}
