//! `phri-record`'s parts, one concern per file: the flags resolved against
//! the configuration ([`settings`]), a recorder per channel ([`channels`],
//! depth frames in [`frames`]), the MCAP file ([`writer`]) and the loop that
//! fills it ([`session`]).

pub mod channels;
pub mod error;
pub mod frames;
pub mod session;
pub mod settings;
pub mod writer;

pub use channels::{recorders, Viz};
pub use error::RecordError;
pub use session::record;
pub use settings::{Flags, Settings};
pub use writer::{metadata, Recording};
