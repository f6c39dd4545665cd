//! Errors of encoding and of the transports.

use std::path::PathBuf;

/// Why a message could not be encoded.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum EncodeError {
    /// A field is NaN or infinite.
    #[error("{field} is not finite ({value})")]
    NonFinite {
        /// The field.
        field: &'static str,
        /// Its value.
        value: f64,
    },
    /// A field does not fit the protocol's range.
    #[error("{field} = {value} is outside the protocol's range [{min}, {max}]")]
    OutOfRange {
        /// The field.
        field: &'static str,
        /// Its value.
        value: f64,
        /// Smallest value the protocol carries.
        min: f64,
        /// Largest value the protocol carries.
        max: f64,
    },
    /// The frame would exceed the protocol's or the buffer's size.
    #[error("the frame does not fit {limit} bytes")]
    TooLong {
        /// The limit (bytes).
        limit: usize,
    },
}

/// Checks that `value` is finite and within `[min, max]`.
pub(crate) fn check_range(
    field: &'static str,
    value: f64,
    min: f64,
    max: f64,
) -> Result<f64, EncodeError> {
    if !value.is_finite() {
        return Err(EncodeError::NonFinite { field, value });
    }
    if !(min..=max).contains(&value) {
        return Err(EncodeError::OutOfRange {
            field,
            value,
            min,
            max,
        });
    }
    Ok(value)
}

/// Error of a transport (serial port, pseudo-terminal).
#[derive(Debug, thiserror::Error)]
pub enum TransportError {
    /// Opening or configuring a serial port failed.
    #[error("serial port {path}: {source}")]
    Serial {
        /// The device path.
        path: PathBuf,
        /// The cause.
        source: serialport::Error,
    },
    /// Reading or writing failed.
    #[error("{what}: {source}")]
    Io {
        /// What was being done, naming the device.
        what: String,
        /// The cause.
        source: std::io::Error,
    },
    /// The device's output buffer could not take a frame (the line is
    /// slower than what is written, or nobody reads): the frame was
    /// dropped, `queued` of its `len` bytes written.
    #[error("{path}: output buffer full: frame of {len} bytes dropped ({queued} bytes queued)")]
    Full {
        /// The device path.
        path: PathBuf,
        /// Bytes of the frame the kernel took.
        queued: usize,
        /// The frame's length.
        len: usize,
    },
    /// A pseudo-terminal could not be created or configured.
    #[error("pseudo-terminal: {step}: {source}")]
    Pty {
        /// The step that failed.
        step: &'static str,
        /// The cause.
        source: std::io::Error,
    },
}
