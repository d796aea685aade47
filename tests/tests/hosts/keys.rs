//! Each host holds only its own private key, as on separate machines.

use caravan_tests::Scenario;
use caravan_tests::hosts::{Hosts, Launcher};

/// Three hosts over QUIC, each machine's folder holding the launch file, the group's authority
/// and its own certificate and key, and nothing of the other hosts': a streams to b and c.
#[test]
fn a_host_holding_only_its_own_key_joins_over_quic() {
    let hosts = Hosts::new("ownkey", &["a", "b", "c"]);
    let hub = hosts.endpoint("a").replace("tcp/", "quic/");
    let tls = |h: &str| {
        format!(
            "tls = {{ ca = \"certs/ca.pem\", certificate = \"certs/{h}.pem\", key = \"certs/{h}.key\" }}"
        )
    };
    let s = Scenario::new(
        "hosts-ownkey",
        &format!(
            r#"clock = "realtime"
duration = "5min"
join_timeout = "20s"

[hosts.a]
listen = ["{hub}"]
{}

[hosts.b]
connect = ["{hub}"]
{}

[hosts.c]
connect = ["{hub}"]
{}

[[process]]
name = "source"
exec = "caravan-testnode stream"
host = "a"
rate = "200Hz"
params = {{ topic = "bulk", count = 200, value = 7.0, readers = 2 }}

[[process]]
name = "sink-b"
exec = "caravan-testnode subscribe"
host = "b"
params = {{ topic = "bulk", count = 200, value = 7.0 }}

[[process]]
name = "sink-c"
exec = "caravan-testnode subscribe"
host = "c"
params = {{ topic = "bulk", count = 200, value = 7.0 }}
"#,
            tls("a"),
            tls("b"),
            tls("c")
        ),
    );
    let data = concat!(env!("CARGO_MANIFEST_DIR"), "/data/tls");
    let launchers: Vec<_> = ["a", "b", "c"]
        .into_iter()
        .map(|h| {
            let machine = s.dir.join(format!("machine-{h}"));
            let certs = machine.join("certs");
            std::fs::create_dir_all(&certs).unwrap();
            std::fs::copy(format!("{data}/fleet-ca.pem"), certs.join("ca.pem")).unwrap();
            for ext in ["pem", "key"] {
                let from = format!("{data}/fleet-{h}.{ext}");
                std::fs::copy(from, certs.join(format!("{h}.{ext}"))).unwrap();
            }
            let file = machine.join("launch.toml");
            std::fs::copy(&s.file, &file).unwrap();
            (h, Launcher::start_file(&hosts, h, &file, &machine, &[]))
        })
        .collect();
    let ended: Vec<_> = launchers
        .into_iter()
        .map(|(h, l)| (h, l.finish()))
        .collect();
    for (host, (code, _)) in &ended {
        assert_eq!(
            *code,
            Some(0),
            "host {host} ({:?}): {ended:#?}",
            hosts.how()
        );
    }
    for h in ["b", "c"] {
        let machine = s.dir.join(format!("machine-{h}"));
        let run = hosts.run_dir(h, &machine);
        let log = std::fs::read_to_string(run.join(format!("logs/sink-{h}.log"))).unwrap();
        assert!(log.contains("received 200 missed 0"), "{log}");
        // No other host's key was ever on this machine.
        let keys: Vec<_> = std::fs::read_dir(machine.join("certs"))
            .unwrap()
            .flatten()
            .map(|e| e.file_name().into_string().unwrap())
            .filter(|n| n.ends_with(".key"))
            .collect();
        assert_eq!(keys, vec![format!("{h}.key")]);
    }
}
