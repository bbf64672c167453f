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
