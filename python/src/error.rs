//! The one error of the binding-free core: the library's message, as text.
//!
//! Every library error (parameters, scenario, trim, model, LTI, ident, ULog,
//! Monte Carlo) already names its file, field and allowed range; the core
//! keeps that message (with any context it adds in front) and the bindings
//! raise it as `helicon.HeliconError`.

/// An error of a core call: the message the Python exception carries.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{0}")]
pub struct Error(pub String);

impl Error {
    /// An error with this message.
    pub fn new(message: impl Into<String>) -> Self {
        Error(message.into())
    }

    /// The message.
    pub fn message(&self) -> &str {
        &self.0
    }

    /// `context: self`.
    #[must_use]
    pub fn context(self, context: &str) -> Self {
        Error(format!("{context}: {}", self.0))
    }
}

/// Any displayable library error as an [`Error`], its source chain joined
/// with `: ` (as `anyhow` prints `{:#}`), so nested causes are not lost.
pub fn from_std(e: &(dyn std::error::Error + 'static)) -> Error {
    let mut text = e.to_string();
    let mut source = e.source();
    while let Some(s) = source {
        let part = s.to_string();
        if !text.contains(&part) {
            text.push_str(": ");
            text.push_str(&part);
        }
        source = s.source();
    }
    Error(text)
}

/// `Result` of the core.
pub type Result<T> = std::result::Result<T, Error>;

/// Convert library errors with `?`.
macro_rules! impl_from {
    ($($t:ty),* $(,)?) => {
        $(impl From<$t> for Error {
            fn from(e: $t) -> Self {
                from_std(&e)
            }
        })*
    };
}

impl_from!(
    helicon_model::ParamError,
    helicon_model::ModelError,
    helicon_model::trim::TrimError,
    helicon_model::ConfigError,
    helicon_lti::LtiError,
    helicon_sim::closed_loop::ClosedLoopError,
    helicon_sim::mc::McError,
    helicon_ident::IdentError,
    helicon_ulog::ReadError,
);

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_source_chain_is_kept() {
        let e = helicon_model::Params::from_file(std::path::Path::new("/nonexistent/p.toml"))
            .map_err(Error::from);
        let msg = e.err().map(|e| e.0).unwrap_or_default();
        assert!(msg.contains("/nonexistent/p.toml"), "{msg}");
        assert!(msg.contains("cannot read"), "{msg}");
        assert!(msg.contains("No such file"), "{msg}");
    }
}
