//! The sans-IO protocol core: one module per protocol family, plus what they share
//! (wire types, decoded values, payload schemas).

pub mod decode;
pub mod error;
pub mod notify;
pub mod relay;
pub mod rsrcp;
pub mod schema;
pub mod table;
pub mod v1;
pub mod v2;
pub mod value;
pub mod wire;
