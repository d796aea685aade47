//! Where elements sit in the URDF text, so that errors can name a line. urdf-rs keeps no
//! positions; a plain scan of the start tags is enough for messages.

/// A start tag: its line (1-based) and the text between `<name` and `>`.
pub struct Tag<'a> {
    pub line: usize,
    body: &'a str,
}

impl Tag<'_> {
    /// The value of attribute `key` (single or double quotes).
    pub fn attribute(&self, key: &str) -> Option<String> {
        let mut rest = self.body;
        while let Some(at) = rest.find(key) {
            let before = rest[..at].chars().last();
            let after = rest[at + key.len()..].trim_start();
            rest = &rest[at + key.len()..];
            if !before.is_some_and(char::is_whitespace) {
                continue;
            }
            let Some(value) = after.strip_prefix('=') else {
                continue;
            };
            let value = value.trim_start();
            let quote = value.chars().next()?;
            if quote != '"' && quote != '\'' {
                return None;
            }
            let end = value[1..].find(quote)?;
            return Some(value[1..1 + end].to_string());
        }
        None
    }
}

/// Every start tag `<element …>` outside comments, in file order.
pub fn elements<'a>(text: &'a str, element: &str) -> Vec<Tag<'a>> {
    let open = format!("<{element}");
    let mut out = Vec::new();
    let mut from = 0;
    while let Some(rel) = text[from..].find(&open) {
        let at = from + rel;
        from = at + open.len();
        let next = text[from..].chars().next();
        if !next.is_some_and(|c| c.is_whitespace() || c == '>' || c == '/') {
            continue;
        }
        if in_comment(text, at) {
            continue;
        }
        let end = text[from..].find('>').map_or(text.len(), |e| from + e);
        out.push(Tag {
            line: text[..at].matches('\n').count() + 1,
            body: &text[from..end],
        });
    }
    out
}

/// Line of the `<element name="name"` start tag.
pub fn line_of(text: &str, element: &str, name: &str) -> Option<usize> {
    elements(text, element)
        .into_iter()
        .find(|t| t.attribute("name").as_deref() == Some(name))
        .map(|t| t.line)
}

/// Where the attribute urdf-rs says is missing (`missing field `size``, with no position)
/// is missing: the line of the first element that needs it and lacks it, and what it is, as
/// `<box> of link 'base' has no size`.
pub fn missing_attribute(text: &str, error: &str) -> Option<(usize, String)> {
    let rest = &error[error.find("missing field ")? + "missing field ".len()..];
    let quote = rest.chars().next()?;
    let name = rest[1..].split(quote).next()?;
    let holders: &[&str] = match name {
        "size" => &["box"],
        "radius" => &["cylinder", "sphere", "capsule"],
        "length" => &["cylinder", "capsule"],
        "filename" => &["mesh"],
        "link" => &["parent", "child"],
        "value" => &["mass"],
        "ixx" | "ixy" | "ixz" | "iyy" | "iyz" | "izz" => &["inertia"],
        "name" | "type" => &["link", "joint"],
        _ => return None,
    };
    let lacking = holders
        .iter()
        .flat_map(|h| elements(text, h).into_iter().map(move |t| (h, t)))
        .filter(|(_, t)| t.attribute(name).is_none())
        .min_by_key(|(_, t)| t.line)?;
    let (holder, tag) = lacking;
    // The link or joint it is part of: the last one opened at or before it.
    let owner = ["link", "joint"]
        .iter()
        .flat_map(|e| elements(text, e).into_iter().map(move |t| (e, t)))
        .filter(|(_, t)| t.line <= tag.line && t.attribute("name").is_some())
        .max_by_key(|(_, t)| t.line)
        .filter(|_| !["link", "joint"].contains(holder))
        .map(|(e, t)| format!(" of {e} '{}'", t.attribute("name").unwrap_or_default()))
        .unwrap_or_default();
    Some((tag.line, format!("<{holder}>{owner} has no {name}")))
}

/// Friction coefficients from Gazebo extensions, `<gazebo reference="link"><mu1>μ</mu1>`:
/// (line, link, the text of mu1).
pub fn gazebo_mu1(text: &str) -> Vec<(usize, String, String)> {
    let mut out = Vec::new();
    for tag in elements(text, "gazebo") {
        let Some(link) = tag.attribute("reference") else {
            continue;
        };
        let start = tag.body.as_ptr() as usize - text.as_ptr() as usize;
        let end = text[start..]
            .find("</gazebo>")
            .map_or(text.len(), |e| start + e);
        let inner = &text[start..end];
        if let Some(open) = inner.find("<mu1>") {
            let value = &inner[open + 5..];
            if let Some(close) = value.find("</mu1>") {
                out.push((tag.line, link, value[..close].trim().to_string()));
            }
        }
    }
    out
}

fn in_comment(text: &str, at: usize) -> bool {
    match text[..at].rfind("<!--") {
        Some(open) => !text[open..at].contains("-->"),
        None => false,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn finds_tags_lines_and_attributes() {
        let text = "<robot>\n<!-- <joint name=\"c\"> -->\n<joint name='a' type=\"fixed\">\n\
                    <jointx name=\"b\"/>\n  <joint\n name=\"b\" type='revolute'/>";
        let tags = elements(text, "joint");
        assert_eq!(tags.len(), 2);
        assert_eq!(tags[0].line, 3);
        assert_eq!(tags[0].attribute("type").as_deref(), Some("fixed"));
        assert_eq!(line_of(text, "joint", "b"), Some(5));
        assert_eq!(line_of(text, "joint", "c"), None);
    }
}
