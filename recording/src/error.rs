//! Why a recording could not be made.

use thiserror::Error;

#[derive(Debug, Error)]
pub enum RecordingError {
    /// The Rerun SDK refused to start a recording or to log some data.
    #[error("cannot record with Rerun: {0}")]
    Stream(#[from] rerun::RecordingStreamError),
    /// The recording could not be encoded as `.rrd`.
    #[error("cannot encode the recording as .rrd: {0}")]
    Encode(#[from] rerun::external::re_log_encoding::EncodeError),
}
