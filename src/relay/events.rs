//! What the relay server reports: one event per thing that happened to a client or its
//! droid, printed as a status line for people or as JSON (`serve --json`).

use crate::model::Model;
use serde::Serialize;

/// What happened, for the status lines and `--json`.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(tag = "event", rename_all = "snake_case")]
pub enum ServerEvent {
    Listening {
        address: String,
        backend: String,
    },
    ClientConnected {
        client: u64,
        peer: String,
        clients: usize,
    },
    /// Over the connection limit: told so and closed.
    ClientRejected {
        peer: String,
        reason: String,
    },
    DroidConnected {
        client: u64,
        peer: String,
        name: String,
        address: String,
        model: Option<&'static str>,
    },
    /// A request the server answered with an ERROR (the droid is held by someone else, a
    /// write failed …).
    RequestFailed {
        client: u64,
        peer: String,
        request: &'static str,
        error: String,
    },
    /// Bytes that are not the protocol (logged; the client is answered, and closed when the
    /// stream cannot be followed).
    ProtocolError {
        client: u64,
        peer: String,
        error: String,
    },
    DroidReleased {
        client: u64,
        name: String,
        address: String,
        /// The stop command was written.
        stopped: bool,
        reason: String,
        /// Where a simulated droid was as its client went (before the stop): the truth a
        /// client's run is judged by.
        #[serde(skip_serializing_if = "Option::is_none")]
        pose: Option<super::backend::Pose>,
    },
    ClientClosed {
        client: u64,
        peer: String,
        reason: String,
        requests: u64,
        writes: u64,
        notifications: u64,
    },
}

impl ServerEvent {
    /// One line for people (stderr).
    pub fn status_line(&self) -> String {
        match self {
            ServerEvent::Listening { address, backend } => {
                format!("serve: listening on {address}, relaying to {backend}")
            }
            ServerEvent::ClientConnected {
                client,
                peer,
                clients,
            } => format!("client {client} {peer}: connected ({clients} connected)"),
            ServerEvent::ClientRejected { peer, reason } => {
                format!("client {peer}: refused: {reason}")
            }
            ServerEvent::DroidConnected {
                client,
                peer,
                name,
                address,
                model,
            } => format!(
                "client {client} {peer}: droid {} {name} ({address}) connected",
                model
                    .and_then(Model::from_id)
                    .map(Model::display_name)
                    .unwrap_or("?")
            ),
            ServerEvent::RequestFailed {
                client,
                peer,
                request,
                error,
            } => format!("client {client} {peer}: {request} failed: {error}"),
            ServerEvent::ProtocolError {
                client,
                peer,
                error,
            } => format!("client {client} {peer}: protocol error: {error}"),
            ServerEvent::DroidReleased {
                client,
                name,
                address,
                stopped,
                reason,
                ..
            } => format!(
                "client {client}: droid {name} ({address}) {}released ({reason})",
                if *stopped { "stopped and " } else { "" }
            ),
            ServerEvent::ClientClosed {
                client,
                peer,
                reason,
                requests,
                writes,
                notifications,
            } => format!(
                "client {client} {peer}: closed ({reason}): {requests} requests, {writes} writes, \
                 {notifications} notifications"
            ),
        }
    }
}
