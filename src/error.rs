//! Errors are values. Bad input (a malformed file, a missing scene, an unknown tracer, invalid TOML)
//! becomes one `Error` naming the file and, where known, the line; `main` prints it and exits with 2.

use std::fmt;
use std::path::{Path, PathBuf};

#[derive(Debug)]
pub enum Error {
    /// Bad input in a file: what is wrong, where.
    Input {
        path: PathBuf,
        line: Option<usize>,
        message: String,
    },
    /// A bad name or value given on the command line or in an experiment (unknown scene, tracer...).
    Usage(String),
    /// A failure that is not the user's input (a library call that failed, a write that failed).
    Runtime(String),
}

pub type Result<T> = std::result::Result<T, Error>;

impl Error {
    pub fn input(path: impl AsRef<Path>, line: Option<usize>, message: impl Into<String>) -> Self {
        Error::Input {
            path: path.as_ref().to_path_buf(),
            line,
            message: message.into(),
        }
    }

    pub fn at_line(path: impl AsRef<Path>, line: usize, message: impl Into<String>) -> Self {
        Self::input(path, Some(line), message)
    }

    pub fn io(path: impl AsRef<Path>, err: std::io::Error) -> Self {
        Self::input(path, None, err.to_string())
    }

    pub fn usage(message: impl Into<String>) -> Self {
        Error::Usage(message.into())
    }

    pub fn runtime(message: impl Into<String>) -> Self {
        Error::Runtime(message.into())
    }

    /// Exit code: 2 for anything the user can fix by changing input, 1 otherwise.
    pub fn exit_code(&self) -> i32 {
        match self {
            Error::Input { .. } | Error::Usage(_) => 2,
            Error::Runtime(_) => 1,
        }
    }
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Error::Input {
                path,
                line: Some(line),
                message,
            } => write!(f, "{}:{}: {}", path.display(), line, message),
            Error::Input {
                path,
                line: None,
                message,
            } => write!(f, "{}: {}", path.display(), message),
            Error::Usage(message) | Error::Runtime(message) => f.write_str(message),
        }
    }
}

impl std::error::Error for Error {}
