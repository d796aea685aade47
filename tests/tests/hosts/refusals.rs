//! Launch files a host refuses before anything starts: bad endpoints, hosts the file lacks or
//! cannot run, and tls tables that do not fit.

use super::two_hosts;
use caravan_tests::Scenario;
use caravan_tests::assert_refused;

#[test]
fn bad_endpoints_are_refused_with_file_line_and_key() {
    for (endpoint, expected) in [
        (
            "udp/127.0.0.1:7447",
            "protocol 'udp' is not available; use tcp",
        ),
        ("tcp/127.0.0.1", "has no port"),
        ("tls/127.0.0.1:7447", "zenoh issue #2557"),
        ("127.0.0.1:7447", "is not an endpoint"),
    ] {
        let s = Scenario::new(
            "hosts-endpoint",
            &two_hosts("realtime", "").replacen(
                "listen = [\"tcp/127.0.0.1:",
                &format!("listen = [\"{endpoint}\", \"tcp/127.0.0.1:"),
                1,
            ),
        );
        let out = s.run(&["--host", "a"]);
        assert_refused(&s, &out, &[expected, "launch.toml:", "listen"]);
    }
    let s = Scenario::new(
        "hosts-endpoint",
        &two_hosts("realtime", "")
            .replace("connect = [\"tcp/127.0.0.1:", "connect = \"tcp/127.0.0.1:"),
    );
    let out = s.run(&["--host", "a"]);
    assert_eq!(out.status.code(), Some(2));
}

#[test]
fn a_host_the_file_lacks_or_cannot_run_is_refused() {
    let s = Scenario::new("hosts-unknown", &two_hosts("realtime", ""));
    let out = s.run(&["--host", "bb"]);
    assert_refused(&s, &out, &["--host bb", "declares no host 'bb'", "'b'"]);
    // Two hosts listen and none says it owns the clock.
    let s = Scenario::new(
        "hosts-lockstep",
        &two_hosts("lockstep", "")
            .replace("connect = ", "listen = [\"tcp/127.0.0.1:1\"]\nconnect = "),
    );
    let out = s.run(&["--host", "a"]);
    assert_refused(&s, &out, &["lockstep group across hosts", "clock = true"]);
    let s = Scenario::new(
        "hosts-two-clocks",
        &two_hosts("lockstep", "").replace(
            "]\n\n[hosts.b]",
            "]\nclock = true\n\n[hosts.b]\nclock = true",
        ),
    );
    let out = s.run(&["--host", "a"]);
    assert_refused(
        &s,
        &out,
        &["launch.toml:", "clock", "host 'a' already has clock = true"],
    );
    // TLS on one host only, and over a tcp/ endpoint.
    let tls = |key: &str| {
        let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/data/tls");
        format!(
            "[hosts.b]\ntls = {{ ca = \"{dir}/ca.pem\", certificate = \"{dir}/host.pem\", key = \"{key}\" }}"
        )
    };
    let host_key = concat!(env!("CARGO_MANIFEST_DIR"), "/data/tls/host.key");
    let s = Scenario::new(
        "hosts-tls-half",
        &two_hosts("realtime", "").replace("[hosts.b]", &tls(host_key)),
    );
    let out = s.run(&["--host", "a"]);
    let expected = [
        "some hosts have a tls table",
        "endpoints must be quic/ADDRESS:PORT",
    ];
    assert_refused(&s, &out, &expected);
    // A host's own tls files must be there; another host's need not (its key stays home).
    let s = Scenario::new(
        "hosts-tls-file",
        &two_hosts("realtime", "join_timeout = \"1s\"")
            .replace("[hosts.a]", &tls(host_key).replace("hosts.b", "hosts.a"))
            .replace("[hosts.b]", &tls("nokey.pem"))
            .replace("tcp/", "quic/"),
    );
    let out = s.run(&["--host", "b"]);
    assert_refused(
        &s,
        &out,
        &["launch.toml:", "key 'key'", "'nokey.pem' is not a file"],
    );
    let out = s.run(&["--host", "a"]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(err.contains("'b' did not join"), "{err}");
    // A tls table without its key is that one problem, not also a host without a table.
    let s = Scenario::new(
        "hosts-tls-keyless",
        &two_hosts("realtime", "")
            .replace("[hosts.a]", &tls(host_key).replace("hosts.b", "hosts.a"))
            .replace("[hosts.b]", &tls(host_key).replace(", key = ", "} #"))
            .replace("tcp/", "quic/"),
    );
    let out = s.run(&["--host", "a"]);
    assert_refused(&s, &out, &["launch.toml:", "'key'"]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!err.contains("some hosts have a tls table"), "{err}");
    assert!(!err.contains("needs a [hosts.b.tls] table"), "{err}");
    let s = Scenario::new(
        "hosts-lockstep-optional",
        &two_hosts("lockstep", "").replace("[hosts.b]", "[hosts.b]\nrequired = false"),
    );
    let out = s.run(&["--host", "a"]);
    assert_refused(&s, &out, &["every host is required", "'b'"]);
    let s = Scenario::new(
        "hosts-unreachable",
        &two_hosts("realtime", "").replace("listen = ", "connect = "),
    );
    let out = s.run(&["--host", "a"]);
    assert_refused(&s, &out, &["no host of", "`listen` endpoints"]);
}
