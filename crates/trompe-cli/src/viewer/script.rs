//! Input scripts for the headless viewer: one event a line, `SECONDS EVENT`, replayed at the
//! frame whose time reaches it.
//!
//! ```text
//! # walk forward for a second, then look right and switch to the impostor method
//! 0.0 down W
//! 1.0 up W
//! 1.0 look 120 0
//! 1.2 tap 2
//! 1.5 scroll -1
//! ```
//!
//! Events: `down KEY`, `up KEY`, `tap KEY` (down then up), `look DX DY` (mouse pixels),
//! `scroll NOTCHES`. Keys: `W A S D Q E` (move), `1`–`9` (methods), `Tab` (orbit), `O` (orbit
//! the next object), `P` (pause),
//! `V` (split), `F12` (screenshot), `C` (save camera), `H` (help).
//!
//! Invariants: events are kept in time order (stable for equal times); every line is either
//! an event, blank or a `#` comment.

use super::{Input, Key};
use std::path::{Path, PathBuf};
use thiserror::Error;

/// A script line that is not an event.
#[derive(Debug, Error)]
#[error("{path}: line {line}: {reason}")]
pub struct ScriptError {
    /// The script file.
    pub path: PathBuf,
    /// 1-based line.
    pub line: usize,
    /// Why.
    pub reason: String,
}

/// Most events a script may hold.
pub const MAX_EVENTS: usize = 1_000_000;

/// A parsed script: events at times, in order.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Script {
    events: Vec<(f32, Input)>,
}

/// The key a script (and the window) names `name`.
pub fn key(name: &str) -> Option<Key> {
    Some(match name.to_ascii_uppercase().as_str() {
        "W" => Key::Forward,
        "S" => Key::Back,
        "A" => Key::Left,
        "D" => Key::Right,
        "E" => Key::Up,
        "Q" => Key::Down,
        "TAB" => Key::Orbit,
        "O" => Key::NextObject,
        "P" => Key::Pause,
        "V" => Key::Split,
        "F12" => Key::Screenshot,
        "C" => Key::SaveCamera,
        "H" => Key::Help,
        digit if digit.len() == 1 => {
            // Keys 1 to 9 are the first nine methods, 0 the tenth.
            let n = digit.parse::<usize>().ok()?;
            Key::Method(if n == 0 { 9 } else { n - 1 })
        }
        _ => return None,
    })
}

impl Script {
    /// Parses `text` (`path` names it in errors).
    pub fn parse(text: &str, path: &Path) -> Result<Script, ScriptError> {
        let mut events = Vec::new();
        for (i, raw) in text.lines().enumerate() {
            let err = |reason: String| ScriptError {
                path: path.to_path_buf(),
                line: i + 1,
                reason,
            };
            let line = raw.trim();
            if line.is_empty() || line.starts_with('#') {
                continue;
            }
            let words: Vec<&str> = line.split_whitespace().collect();
            let time: f32 = words[0]
                .parse()
                .ok()
                .filter(|t: &f32| t.is_finite() && *t >= 0.0)
                .ok_or_else(|| err(format!("{:?} is not a time in seconds", words[0])))?;
            let number = |w: Option<&&str>| -> Result<f32, ScriptError> {
                w.and_then(|w| w.parse::<f32>().ok())
                    .filter(|x| x.is_finite())
                    .ok_or_else(|| err(format!("{line:?}: expected a number")))
            };
            let named = |w: Option<&&str>| -> Result<Key, ScriptError> {
                let name = w.ok_or_else(|| err("a key name is missing".into()))?;
                key(name).ok_or_else(|| err(format!("unknown key {name:?}")))
            };
            let parsed = match (words.get(1).copied(), words.len()) {
                (Some("down"), 3) => vec![Input::Down(named(words.get(2))?)],
                (Some("up"), 3) => vec![Input::Up(named(words.get(2))?)],
                (Some("tap"), 3) => {
                    let k = named(words.get(2))?;
                    vec![Input::Down(k), Input::Up(k)]
                }
                (Some("look"), 4) => {
                    vec![Input::Look(number(words.get(2))?, number(words.get(3))?)]
                }
                (Some("scroll"), 3) => vec![Input::Scroll(number(words.get(2))?)],
                _ => {
                    return Err(err(format!(
                        "{line:?}: expected SECONDS down|up|tap KEY, look DX DY or scroll N"
                    )));
                }
            };
            if events.len() + parsed.len() > MAX_EVENTS {
                return Err(err(format!("more than {MAX_EVENTS} events")));
            }
            events.extend(parsed.into_iter().map(|e| (time, e)));
        }
        events.sort_by(|a, b| a.0.total_cmp(&b.0));
        Ok(Script { events })
    }

    /// Reads and parses a script file.
    pub fn load(path: &Path) -> Result<Script, ScriptError> {
        let text = std::fs::read_to_string(path).map_err(|e| ScriptError {
            path: path.to_path_buf(),
            line: 0,
            reason: e.to_string(),
        })?;
        Self::parse(&text, path)
    }

    /// The events at times in `[from, to)`.
    pub fn between(&self, from: f32, to: f32) -> impl Iterator<Item = Input> + '_ {
        self.events
            .iter()
            .filter(move |(t, _)| *t >= from && *t < to)
            .map(|(_, e)| *e)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scripts_parse_and_refuse_with_the_line() {
        let s = Script::parse(
            "# c\n0 down W\n\n1.5 tap 2\n0.5 look 3 -4\n",
            Path::new("k"),
        )
        .unwrap();
        let all: Vec<_> = s.between(0.0, 10.0).collect();
        assert_eq!(
            all,
            [
                Input::Down(Key::Forward),
                Input::Look(3.0, -4.0),
                Input::Down(Key::Method(1)),
                Input::Up(Key::Method(1)),
            ]
        );
        let e = Script::parse("0 down W\nx down W\n", Path::new("k")).unwrap_err();
        assert_eq!(e.line, 2);
        assert!(Script::parse("0 down Z\n", Path::new("k")).is_err());
        assert!(Script::parse("0 look 1\n", Path::new("k")).is_err());
    }
}
