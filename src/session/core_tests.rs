//! The session's timing rules on plain time values: no runtime, no link.
