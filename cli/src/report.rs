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
            let len = loc.span.len().max(1);
            // No diagnostic code: the first line a user reads is the message.
            let diag = MietteDiagnostic::new(format!("{}: {}", loc, message))
                .with_label(LabeledSpan::at(loc.span.start..loc.span.start + len, "here"));
            let source = NamedSource::new(loc.path.display().to_string(), loc.text.to_string());
            Report::new(diag).with_source_code(source)
        }
        None => miette::miette!("{e}"),
    }
}

/// Longest source line shown with its offending value underlined.
const MAX_SHOWN_LINE: usize = 1000;

/// Characters on the line of `text` that holds byte `at`.
fn line_length(text: &str, at: usize) -> usize {
    let at = at.min(text.len());
    let start = text[..at].rfind('\n').map_or(0, |i| i + 1);
    let end = text[at..].find('\n').map_or(text.len(), |i| at + i);
    text.get(start..end).map_or(0, |line| line.chars().count())
}
