//! The TCP relay of GATT operations that spherov2.py defined (`spherov2.adapter.tcp_server`
//! and `tcp_adapter`): [`protocol`] is its sans-IO codec; [`server`] is `droidctl serve`,
//! relaying to droids behind a [`backend::GattBackend`]: Bluetooth LE ([`ble_backend`]) or
//! simulated droids at the GATT level ([`sim_backend`]). The client side is
//! [`crate::link::remote`].

pub mod backend;
pub mod ble_backend;
pub mod events;
pub mod record;
pub mod serial_backend;
pub mod server;
pub mod sim_backend;
mod stream;
