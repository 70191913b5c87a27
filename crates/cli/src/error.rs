//! The CLI's error type and its mapping to exit codes (README.md, "Exit codes").

use std::fmt;

/// Why a command stopped; each kind maps to one exit code.
#[derive(Debug)]
pub(crate) enum CliError {
    /// Bad usage or bad input (unknown key, unreadable file, impossible parameter): exit code 2.
    Input(String),
    /// A statistical test failed: exit code 1.
    TestFailed(String),
    /// `validate` ran no test: every case was skipped (no sampler applied to the targets):
    /// exit code 3, so a run that checked nothing is never taken for a pass.
    NothingTested(String),
}

impl CliError {
    /// The process exit code for this error.
    pub(crate) fn exit_code(&self) -> i32 {
        match self {
            CliError::Input(_) => 2,
            CliError::TestFailed(_) => 1,
            CliError::NothingTested(_) => 3,
        }
    }

    /// Builds an input error from anything printable.
    pub(crate) fn input(e: impl fmt::Display) -> Self {
        // One line: the CLI contract promises a one-line reason.
        CliError::Input(e.to_string().replace('\n', "; "))
    }
}

impl fmt::Display for CliError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            CliError::Input(m) | CliError::TestFailed(m) | CliError::NothingTested(m) => {
                f.write_str(m)
            }
        }
    }
}

/// Result alias of the CLI commands.
pub(crate) type CliResult<T> = Result<T, CliError>;
