//! Scripted input for `kage view --script FILE`: the events a user would
//! make, one per line, for tests and recordings. Inputs arrive one a step
//! rendered, while it renders, as a moving mouse's events do (120 `drag`
//! lines: a 120-frame orbit).
//!
//! ```text
//! # a comment
//! drag left 40 0          # button (left, middle, right), dx, dy pixels; add "shift"
//! wheel 2                 # steps in (negative: out)
//! key 1                   # a key: a letter or digit, home, f12, esc
//! wait                    # until the image is fully refined
//! wait 8                  # until 8 jittered passes are averaged on screen
//! sleep 0.5               # seconds
//! screenshot shot.png     # write the image shown (no HUD) to a PNG
//! capture window.png      # write the window as it looks (HUD and all)
//! copy edited.toml scene.toml   # copy a file (paths relative to the script)
//! drop other.toml         # a file dropped on the window
//! quit
//! ```
//!
//! A change on disk reaches the viewer a moment after it is made: after
//! `copy`, `sleep` a little before `wait`.

use std::path::{Path, PathBuf};

use super::state::{Button, Input, Key};

/// One line of a script.
#[derive(Debug, Clone, PartialEq)]
pub enum Action {
    /// An input event.
    Input(Input),
    /// Wait until the refinement is done.
    Wait,
    /// Wait until this many jittered passes are averaged on screen.
    WaitPasses(u32),
    /// Wait this many seconds.
    Sleep(f32),
    /// Write the image shown to this PNG.
    Screenshot(PathBuf),
    /// Write the window's contents (the image with what is drawn over it).
    Capture(PathBuf),
    /// Copy a file over another (a live-reload test's edit).
    Copy(PathBuf, PathBuf),
    /// Close the window.
    Quit,
}

/// Every action a script line may start with, and how it is written (the
/// `--script` help names each of them: a test holds it to this list).
pub const ACTIONS: [(&str, &str); 10] = [
    ("drag", "drag left DX DY [shift]"),
    ("wheel", "wheel N"),
    ("key", "key K"),
    ("drop", "drop FILE"),
    ("wait", "wait N"),
    ("sleep", "sleep S"),
    ("screenshot", "screenshot FILE"),
    ("capture", "capture FILE"),
    ("copy", "copy FROM TO"),
    ("quit", "quit"),
];

/// A script's actions.
///
/// # Errors
///
/// A line that is not an action, as `file:line: what is wrong`.
pub fn parse(text: &str, file: &Path) -> Result<Vec<Action>, String> {
    let base = file.parent().unwrap_or(Path::new("."));
    let mut out = Vec::new();
    for (n, line) in text.lines().enumerate() {
        let line = line.split('#').next().unwrap_or("").trim();
        if line.is_empty() {
            continue;
        }
        let words: Vec<&str> = line.split_whitespace().collect();
        let action = action(&words, base).map_err(|e| format!("{}:{}: {e}", file.display(), n + 1))?;
        out.push(action);
    }
    Ok(out)
}

fn action(words: &[&str], base: &Path) -> Result<Action, String> {
    let number = |w: Option<&&str>, what: &str| -> Result<f32, String> {
        let w = w.ok_or(format!("{} needs {what}", words[0]))?;
        w.parse::<f32>().ok().filter(|v| v.is_finite()).ok_or(format!("{what} must be a number, not `{w}`"))
    };
    let path = |w: Option<&&str>| -> Result<PathBuf, String> {
        w.map(|w| base.join(w)).ok_or(format!("{} needs a path", words[0]))
    };
    Ok(match words[0] {
        "drag" => {
            let button = match words.get(1).copied() {
                Some("left") => Button::Left,
                Some("middle") => Button::Middle,
                Some("right") => Button::Right,
                other => return Err(format!("drag needs a button (left, middle, right), not {other:?}")),
            };
            let (dx, dy) = (number(words.get(2), "dx")?, number(words.get(3), "dy")?);
            let shift = match words.get(4).copied() {
                None => false,
                Some("shift") => true,
                Some(w) => return Err(format!("drag takes \"shift\" after dx dy, not `{w}`")),
            };
            Action::Input(Input::Drag { button, dx, dy, shift })
        }
        "wheel" => Action::Input(Input::Wheel(number(words.get(1), "steps")?)),
        "key" => Action::Input(Input::Key(key(words.get(1).copied().ok_or("key needs a key")?)?)),
        "wait" => match words.get(1) {
            None => Action::Wait,
            passes => Action::WaitPasses(number(passes, "passes")?.max(0.0) as u32),
        },
        "drop" => Action::Input(Input::Dropped(path(words.get(1))?)),
        "sleep" => Action::Sleep(number(words.get(1), "seconds")?.max(0.0)),
        "screenshot" => Action::Screenshot(path(words.get(1))?),
        "capture" => Action::Capture(path(words.get(1))?),
        "copy" => Action::Copy(path(words.get(1))?, path(words.get(2))?),
        "quit" => Action::Quit,
        other => {
            let known: Vec<&str> = ACTIONS.iter().map(|(word, _)| *word).collect();
            return Err(format!("unknown action `{other}` ({})", known.join(", ")));
        }
    })
}

/// The key a script names.
fn key(name: &str) -> Result<Key, String> {
    let lower = name.to_ascii_lowercase();
    match lower.as_str() {
        "home" => Ok(Key::Home),
        "f12" => Ok(Key::F12),
        "esc" | "escape" => Ok(Key::Escape),
        k if k.chars().count() == 1 => Ok(Key::Char(k.chars().next().expect("one char"))),
        _ => Err(format!("unknown key `{name}` (a letter or digit, home, f12, esc)")),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_script_reads_into_actions() {
        let text = "# orbit, then look\ndrag left 40 -2\ndrag middle 1 2 shift\nwheel -1.5\nkey F\nkey home\n\
                    wait\nwait 8\nsleep 0.25\nscreenshot out/a.png  # the result\ncapture w.png\ncopy b.toml a.toml\n\
                    drop c.toml\nquit\n";
        let actions = parse(text, Path::new("tests/run.script")).unwrap();
        assert_eq!(
            actions,
            vec![
                Action::Input(Input::Drag { button: Button::Left, dx: 40.0, dy: -2.0, shift: false }),
                Action::Input(Input::Drag { button: Button::Middle, dx: 1.0, dy: 2.0, shift: true }),
                Action::Input(Input::Wheel(-1.5)),
                Action::Input(Input::Key(Key::Char('f'))),
                Action::Input(Input::Key(Key::Home)),
                Action::Wait,
                Action::WaitPasses(8),
                Action::Sleep(0.25),
                Action::Screenshot(PathBuf::from("tests/out/a.png")),
                Action::Capture(PathBuf::from("tests/w.png")),
                Action::Copy(PathBuf::from("tests/b.toml"), PathBuf::from("tests/a.toml")),
                Action::Input(Input::Dropped(PathBuf::from("tests/c.toml"))),
                Action::Quit,
            ]
        );
    }

    #[test]
    fn a_bad_line_is_named_with_its_file_and_line() {
        for (text, what) in [
            ("wait\ndrag up 1 2", "run.script:2: drag needs a button"),
            ("wheel lots", "run.script:1: steps must be a number, not `lots`"),
            ("key", "run.script:1: key needs a key"),
            ("key pageup", "run.script:1: unknown key `pageup`"),
            ("\n\nfly 3", "run.script:3: unknown action `fly`"),
            ("drag left 1 2 ctrl", "run.script:1: drag takes \"shift\""),
            ("screenshot", "run.script:1: screenshot needs a path"),
            ("wait many", "run.script:1: passes must be a number"),
            ("drop", "run.script:1: drop needs a path"),
        ] {
            let e = parse(text, Path::new("run.script")).unwrap_err();
            assert!(e.starts_with(what), "{text:?}: {e}");
        }
    }
}
