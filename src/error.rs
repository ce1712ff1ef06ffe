//! One error type for everything a user can get wrong.
//!
//! Every message names the file and, where one applies, the key or line, so
//! that a user can go straight to the mistake. The CLI prints the message on
//! one line and exits with code 2.

use std::fmt;
use std::path::Path;

/// What an [`InputError`] names as its "file" when the fault is a flag.
pub const COMMAND_LINE: &str = "<command line>";

/// A problem with something the user handed us: a scene, mesh, partial file or flag.
#[derive(Debug, Clone, PartialEq)]
pub struct InputError {
    /// The file at fault (or `<command line>` for a flag).
    pub file: String,
    /// The TOML key path (`objects[2].sphere.radius`), `line N`, or empty.
    pub location: String,
    /// The line of a scene file that `location` names, where known.
    pub line: Option<usize>,
    pub message: String,
    /// Further mistakes found in the same run (a scene file's, in file
    /// order), each shown on a line of its own after this one, so that one
    /// run names them all. Empty for almost every error.
    pub more: Vec<InputError>,
}

impl InputError {
    pub fn new(
        file: impl AsRef<Path>,
        location: impl Into<String>,
        message: impl Into<String>,
    ) -> Self {
        Self {
            file: file.as_ref().display().to_string(),
            location: location.into(),
            line: None,
            message: message.into(),
            more: Vec::new(),
        }
    }

    /// An error in a flag of the command line: `location` is the flag as
    /// given, with its value (`--spp 0`, `--set render.spp=0`).
    pub fn flag(location: impl Into<String>, message: impl Into<String>) -> Self {
        Self::new(COMMAND_LINE, location, message)
    }

    /// An error about the file as a whole (unreadable, wrong format).
    pub fn file(file: impl AsRef<Path>, message: impl Into<String>) -> Self {
        Self::new(file, "", message)
    }

    /// One error holding `errors` in the order given (the first shown
    /// first, the others in [`InputError::more`]); `None` if there are none.
    pub fn all(errors: Vec<InputError>) -> Option<InputError> {
        let mut errors = errors.into_iter().flat_map(InputError::into_each);
        let mut first = errors.next()?;
        first.more = errors.collect();
        Some(first)
    }

    /// This error and its [`more`](InputError::more), one by one.
    pub fn into_each(mut self) -> Vec<InputError> {
        let more = std::mem::take(&mut self.more);
        let mut each = vec![self];
        each.extend(more.into_iter().flat_map(InputError::into_each));
        each
    }

    /// The same error, placed on `line` of its file.
    pub fn on_line(mut self, line: Option<usize>) -> Self {
        self.line = line;
        self
    }
}

impl fmt::Display for InputError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        // Keep it on one line: multi-line parser messages are folded.
        let message = self
            .message
            .split_whitespace()
            .collect::<Vec<_>>()
            .join(" ");
        write!(f, "{}: ", self.file)?;
        if let Some(line) = self.line {
            write!(f, "line {line}: ")?;
        }
        if !self.location.is_empty() {
            write!(f, "{}: ", self.location)?;
        }
        f.write_str(&message)?;
        // One line per mistake: the CLI prefixes each with `error: `.
        for more in &self.more {
            write!(f, "\n{more}")?;
        }
        Ok(())
    }
}

impl std::error::Error for InputError {}

pub type InputResult<T> = Result<T, InputError>;

/// An I/O error's text without the "(os error 2)" tail, for one-line
/// messages such as `cannot read: No such file or directory`.
pub fn io_message(e: &std::io::Error) -> String {
    let text = e.to_string();
    match text.find(" (os error") {
        Some(i) => text[..i].to_string(),
        None => text,
    }
}
