//! Benchmarks run briefly and write their files. They assert nothing about time.

use caravan_tests::workspace_bin;
use std::collections::BTreeSet;
use std::process::Command;

const TRANSPORTS: [&str; 9] = [
    "caravan-event",
    "caravan-poll",
    "iceoryx2-event",
    "iceoryx2-poll",
    "uds",
    "tcp",
    "udp",
    "zenoh",
    "zenoh-shm",
];

#[test]
fn bench_transport_quick_writes_csv_and_plot() {
    let out = std::env::temp_dir().join(format!("caravan-bench-test-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&out);
    let run = Command::new(workspace_bin("caravan"))
        .args(["bench", "transport", "--quick", "--out"])
        .arg(&out)
        .output()
        .expect("cannot run caravan bench transport");
    let stdout = String::from_utf8_lossy(&run.stdout);
    assert!(
        run.status.success(),
        "bench failed\nstdout:\n{stdout}\nstderr:\n{}",
        String::from_utf8_lossy(&run.stderr)
    );

    let csv = std::fs::read_to_string(out.join("transport.csv")).expect("transport.csv");
    let comments: Vec<&str> = csv.lines().filter(|l| l.starts_with('#')).collect();
    assert!(comments.iter().any(|l| l.starts_with("# cpu: ")), "{csv}");
    assert!(
        comments.iter().any(|l| l.starts_with("# kernel: ")),
        "{csv}"
    );
    let mut lines = csv.lines().filter(|l| !l.starts_with('#'));
    let header: Vec<&str> = lines.next().expect("CSV header").split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).expect(name);
    let (transport, bytes, p50, status) = (
        col("transport"),
        col("payload_bytes"),
        col("p50_ns"),
        col("status"),
    );
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    let sizes: BTreeSet<u64> = rows.iter().map(|r| r[bytes].parse().unwrap()).collect();
    assert!(sizes.contains(&16) && sizes.len() >= 2, "sizes {sizes:?}");
    for t in TRANSPORTS {
        for &size in &sizes {
            let row = rows
                .iter()
                .find(|r| r[transport] == t && r[bytes] == size.to_string())
                .unwrap_or_else(|| panic!("no row for {t} at {size} B\n{csv}"));
            if row[status] == "ok" {
                assert!(row[p50].parse::<u64>().unwrap() > 0, "{row:?}");
            } else {
                assert!(row[status].starts_with("unsupported"), "{row:?}");
            }
        }
    }
    assert_eq!(rows.len(), TRANSPORTS.len() * sizes.len(), "{csv}");

    let svg = std::fs::read_to_string(out.join("transport.svg")).expect("transport.svg");
    assert!(svg.starts_with("<svg") && svg.trim_end().ends_with("</svg>"));
    for t in TRANSPORTS {
        assert!(svg.contains(t), "the plot's legend lacks {t}");
    }
    assert!(stdout.contains("kernel"), "{stdout}");
    let _ = std::fs::remove_dir_all(&out);
}
