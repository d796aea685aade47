//! Failed TLS handshakes, named. zenoh says why a connection failed only in its log: the
//! listening side logs the refused certificate (without the peer's address), the dialling side
//! logs the endpoint it could not reach. The launcher taps those events
//! ([`caravan::log::tap`]) and turns them into messages that name the host: the dialled host
//! by its endpoint in the launch file, a refused dialler as one of the hosts not yet joined.

use caravan_launch::model::HostSpec;
use std::collections::BTreeMap;

/// A handshake that failed, as one side saw it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Failure {
    /// This host refused a peer's certificate (it listens; the peer dialled).
    Refused { reason: String },
    /// Dialling `host` at `endpoint` failed during the handshake.
    Dial {
        host: String,
        endpoint: String,
        reason: String,
    },
}

impl Failure {
    /// One line for the console; `missing` are the hosts that have not joined, one of which
    /// dialled when this host refused a certificate.
    pub fn describe(&self, missing: &[String]) -> String {
        match self {
            Failure::Refused { reason } => {
                let who = match missing {
                    [] => "a peer".to_string(),
                    [one] => format!("a peer (host '{one}', the only one not joined)"),
                    many => format!(
                        "a peer (one of the hosts not joined: {})",
                        super::quoted(many)
                    ),
                };
                format!(
                    "TLS handshake failed: this host refused the certificate of {who}: {reason}{}",
                    hint(reason)
                )
            }
            Failure::Dial {
                host,
                endpoint,
                reason,
            } => format!(
                "TLS handshake with host '{host}' ({endpoint}) failed: {reason}{}",
                hint(reason)
            ),
        }
    }
}

/// What a reason most likely means for the group's certificates.
fn hint(reason: &str) -> &'static str {
    if reason.contains("UnknownIssuer") {
        " (the certificate is not signed by the group's authority, the tls table's `ca`)"
    } else if reason.contains("connection lost") {
        " (the connection closed in the handshake: that host most likely refused this host's certificate; it says why)"
    } else if reason.contains("NotValidForName") {
        " (the certificate does not name the address it is reached at: add it to the certificate's subjectAltName)"
    } else if reason.contains("Expired") {
        " (a certificate has expired)"
    } else {
        ""
    }
}

/// Reads a tapped zenoh event (`target`, `message`) of a launcher whose `hosts` use TLS.
pub fn parse(hosts: &BTreeMap<String, HostSpec>, target: &str, message: &str) -> Option<Failure> {
    if target.starts_with("zenoh_link_commons::quic") && message.contains("QUIC acceptor failed") {
        // `TransportError(Error { code: Code::crypto(30), frame: None, reason: "…" }) at …`
        let reason = between(message, "reason: \"", "\"")?;
        let tls = message.contains("crypto") || reason.contains("certificate");
        return tls.then(|| Failure::Refused {
            reason: reason.to_string(),
        });
    }
    // `Unable to connect to configured peer quic/10.88.0.1:7447! ERROR at FILE:LINE.. Retry in 1s.`
    let rest = message.strip_prefix("Unable to connect to configured peer ")?;
    let (endpoint, error) = rest.split_once("! ")?;
    let error = error
        .split(" at ")
        .next()
        .unwrap_or(error)
        .trim_end_matches('.');
    let handshake = [
        "certificate",
        "connection lost",
        "crypto",
        "handshake",
        "TLS",
    ]
    .iter()
    .any(|w| error.contains(w));
    if !handshake {
        // Nobody listening yet, or a timeout: the join wait reports those.
        return None;
    }
    let host = hosts
        .iter()
        .find(|(_, h)| h.listen.iter().any(|l| l == endpoint))
        .map(|(name, _)| name.clone())?;
    Some(Failure::Dial {
        host,
        endpoint: endpoint.to_string(),
        reason: error
            .rsplit(": ")
            .next()
            .unwrap_or(error)
            .trim()
            .to_string(),
    })
}

fn between<'a>(text: &'a str, start: &str, end: &str) -> Option<&'a str> {
    let from = text.find(start)? + start.len();
    let len = text[from..].find(end)?;
    Some(&text[from..from + len])
}

#[cfg(test)]
mod tests {
    use super::*;

    fn group() -> BTreeMap<String, HostSpec> {
        let a = HostSpec {
            listen: vec!["quic/10.88.0.1:7447".into()],
            ..HostSpec::default()
        };
        BTreeMap::from([("a".into(), a), ("b".into(), HostSpec::default())])
    }

    #[test]
    fn a_refused_certificate_is_read_from_the_listeners_log() {
        let m = r#"QUIC acceptor failed: TransportError(Error { code: Code::crypto(30), frame: None, reason: "invalid peer certificate: UnknownIssuer" }) at src/quic/unicast.rs:686. Hint: increase the system open file limit."#;
        let f = parse(&group(), "zenoh_link_commons::quic::unicast", m).unwrap();
        let reason = "invalid peer certificate: UnknownIssuer".to_string();
        assert_eq!(f, Failure::Refused { reason });
        let line = f.describe(&["b".into()]);
        assert!(line.contains("host 'b', the only one not joined"), "{line}");
        assert!(
            line.contains("not signed by the group's authority"),
            "{line}"
        );
    }

    #[test]
    fn a_failed_dial_names_the_host_by_its_endpoint() {
        let m = "Unable to connect to configured peer quic/10.88.0.1:7447! Read error on QUIC link 0.0.0.0:34723 => 10.88.0.1:7447: connection lost at /x/unicast.rs:135.. Retry in 1s.";
        let f = parse(&group(), "zenoh::net::runtime::orchestrator", m).unwrap();
        let Failure::Dial { host, reason, .. } = &f else {
            panic!("{f:?}")
        };
        assert_eq!((host.as_str(), reason.as_str()), ("a", "connection lost"));
        assert!(f.describe(&[]).contains("host 'a' (quic/10.88.0.1:7447)"));
    }

    #[test]
    fn a_peer_not_up_yet_is_no_handshake_failure() {
        let m = "Unable to connect to configured peer quic/10.88.0.1:7447! deadline has elapsed at /x/manager.rs:901.. Retry in 1s.";
        assert_eq!(
            parse(&group(), "zenoh::net::runtime::orchestrator", m),
            None
        );
        let other = "QUIC acceptor failed: Too many open files";
        assert_eq!(
            parse(&group(), "zenoh_link_commons::quic::unicast", other),
            None
        );
    }
}
