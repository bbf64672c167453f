//! Library errors → miette reports: scene-file and `.csg` errors show the offending line with
//! the value underlined; every other error keeps its message.

use kage::Error;
use miette::{LabeledSpan, MietteDiagnostic, NamedSource, Report};

/// Turns a library error into a report for the terminal.
pub fn to_report(e: Error) -> Report {
    let located = match &e {
        Error::SceneSyntax { location, message }
        | Error::SceneInvalid { location, message }
        | Error::CsgSyntax { location, message }
        | Error::CsgInvalid { location, message } => Some((location.clone(), message.clone())),
        _ => None,
    };
    match located {
        // A line too long to show (minified files; the report formatter
        // also fails past column 65,535): the message with its location alone.
        Some((loc, message)) if line_length(&loc.text, loc.span.start) > MAX_SHOWN_LINE => {
            miette::miette!("{}: {}", loc, message)
        }
        Some((loc, message)) => {
            let (text, span) = excerpt(&loc.text, loc.span.clone());
            // No diagnostic code: the first line a user reads is the message.
            let diag = MietteDiagnostic::new(format!("{}: {}", loc, message))
                .with_label(LabeledSpan::at(span.start..span.start + span.len().max(1), "here"));
            let source = NamedSource::new(loc.path.display().to_string(), text);
            Report::new(diag).with_source_code(source)
        }
        None => miette::miette!("{e}"),
    }
}

/// Longest source line shown with its offending value underlined.
const MAX_SHOWN_LINE: usize = 1000;

/// Characters shown either side of the offending text on its line.
const CONTEXT: usize = 40;

/// What a report shows of `text` around `span`: the lines before it left
/// blank (so line numbers stay), its own line without its indentation
/// (OpenSCAD's `.csg` indents a node a tab per level, hundreds deep), cut
/// to [`CONTEXT`] characters either side of the span (which ends with its
/// line), and nothing after; with the span in that text.
fn excerpt(text: &str, span: std::ops::Range<usize>) -> (String, std::ops::Range<usize>) {
    let at = span.start.min(text.len());
    let line_start = text[..at].rfind('\n').map_or(0, |i| i + 1);
    let line_end = text[at..].find('\n').map_or(text.len(), |i| at + i);
    let line = &text[line_start..line_end];
    let indent = line.len() - line.trim_start().len();
    let from_in_line = at - line_start;
    let before = &line[indent..from_in_line];
    let first = indent + before.char_indices().rev().nth(CONTEXT - 1).map_or(0, |(i, _)| i);
    let span_end = span.end.clamp(at, line_end) - line_start;
    let last = line[span_end..].char_indices().nth(CONTEXT).map_or(line.len(), |(i, _)| span_end + i);
    let mut out = "\n".repeat(text[..line_start].matches('\n').count());
    let lead = if first > indent { "… " } else { "" };
    out.push_str(lead);
    let base = out.len();
    out.push_str(&line[first..last]);
    if last < line.len() {
        out.push_str(" …");
    }
    let start = base + from_in_line - first;
    (out, start..start + (span_end - from_in_line))
}

/// Characters on the line of `text` that holds byte `at`.
fn line_length(text: &str, at: usize) -> usize {
    let at = at.min(text.len());
    let start = text[..at].rfind('\n').map_or(0, |i| i + 1);
    let end = text[at..].find('\n').map_or(text.len(), |i| at + i);
    text.get(start..end).map_or(0, |line| line.chars().count())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_excerpt_drops_indentation_and_far_text_but_keeps_the_line_number() {
        let deep = format!("group() {{\n{}cube(size = [1, 1, 1], center = maybe);\n}}\n", "\t".repeat(240));
        let at = deep.find("maybe").unwrap();
        let (text, span) = excerpt(&deep, at..at + 5);
        assert_eq!(&text[span.clone()], "maybe");
        assert_eq!(text.lines().count(), 2, "{text:?}");
        assert!(text.lines().nth(1).unwrap().starts_with("cube(size"), "{text:?}");
        let long = format!("{}x{}", "a, ".repeat(200), ", b".repeat(200));
        let at = long.find('x').unwrap();
        let (text, span) = excerpt(&long, at..at + 1);
        assert_eq!(&text[span], "x");
        assert!(text.chars().count() < 100 && text.starts_with("… ") && text.ends_with(" …"), "{text}");
    }
}
