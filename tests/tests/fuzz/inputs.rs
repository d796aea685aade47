//! Mutation fuzzing of the inputs beyond the loaders of `fuzz.rs` (issue 49):
//! - recordings as `caravan info` ([`describe`]), `caravan play` ([`read_recording`]) and
//!   `caravan resim` ([`attached_launch_file`], then the attached launch file loaded) read
//!   them: a real recording, and copies of it rewritten uncompressed, with lz4, and with zstd
//!   frames that store their bytes, each cut short, with bits flipped and bytes overwritten
//!   (inside chunks too), garbage appended, the summary zeroed and hostile lengths and offsets;
//! - launch files with `[hosts]` tables (endpoints, tls, clock, required, cpu_slowdown,
//!   `group.host_lease`), loaded, then `check_host` and `session_config` for each host;
//! - the UAV agent's policy (weights) files, read by [`Mlp::parse`].
//!
//! Each must give a value or an error, never panic, in time bounded by the input's size.
//! CI runs 4,000 recordings, 5,000 hosts files and 1,000 policy files (at most about 15 s each
//! in a debug build on two cores); `PROPTEST_CASES=… cargo nextest run --release -p caravan-tests --test
//! fuzz -E 'test(/fuzz_recording|fuzz_hosts|fuzz_policy/)'` is the long run (docs/reliability.md).

use super::config;
use caravan_bridge::{check_host, session_config};
use caravan_group::info::describe;
use caravan_group::play::read_recording;
use caravan_group::resim::attached_launch_file;
use caravan_launch::load::load_source;
use caravan_report::fuzz::mutate;
use caravan_tests::{PINGPONG, Scenario, caravan, workspace_root};
use caravan_uav::mlp::Mlp;
use proptest::prelude::*;
use std::ops::Range;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;
use std::time::{Duration, Instant};

/// The most any one input may take: far more than any takes, far less than a hang.
const BOUND: Duration = Duration::from_secs(10);

/// A small seeded generator (splitmix64): a failing input is reproduced from its seed.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// A number in `0..n` (0 when `n` is 0).
    fn below(&mut self, n: usize) -> usize {
        if n == 0 {
            0
        } else {
            (self.next() % n as u64) as usize
        }
    }

    fn bytes(&mut self, n: usize) -> Vec<u8> {
        (0..n).map(|_| self.next() as u8).collect()
    }
}

/// The executable of any program name: the fuzzed files are loaded, never run.
fn any_program(name: &str) -> Option<PathBuf> {
    Some(PathBuf::from(name))
}

// ---------------------------------------------------------------------------------------------
// Recordings

const OP_FOOTER: u8 = 0x02;
const OP_CHUNK: u8 = 0x06;
const OP_DATA_END: u8 = 0x0F;
/// A zstd frame's magic and a descriptor of one segment with a 4-byte content size.
const STORED_ZSTD: [u8; 5] = [0x28, 0xB5, 0x2F, 0xFD, 0xA0];

/// Where an MCAP file's parts are: every record (top-level, and inside chunks whose records
/// can be seen: uncompressed or stored), every chunk, the summary section and the footer.
#[derive(Default)]
struct Layout {
    records: Vec<usize>,
    chunks: Vec<Range<usize>>,
    summary: Option<Range<usize>>,
    footer: Option<usize>,
}

fn u64_at(b: &[u8], at: usize) -> Option<u64> {
    Some(u64::from_le_bytes(b.get(at..at + 8)?.try_into().ok()?))
}

fn u32_at(b: &[u8], at: usize) -> Option<usize> {
    Some(u32::from_le_bytes(b.get(at..at + 4)?.try_into().ok()?) as usize)
}

fn layout(b: &[u8]) -> Layout {
    let mut l = Layout::default();
    walk(b, 8..b.len(), &mut l, true);
    l
}

fn walk(b: &[u8], span: Range<usize>, l: &mut Layout, top: bool) {
    let mut at = span.start;
    while let Some(len) = u64_at(b, at + 1) {
        let next = usize::try_from(len).map_or(usize::MAX, |n| n.saturating_add(at + 9));
        if next > span.end {
            return;
        }
        l.records.push(at);
        if top && b[at] == OP_CHUNK {
            l.chunks.push(at..next);
            // Start and end time, uncompressed size and CRC, compression, records' length.
            let name = at + 9 + 28;
            let n = u32_at(b, name).unwrap_or(0);
            let records = name + 4 + n + 8;
            match b.get(name + 4..name + 4 + n).unwrap_or(b"?") {
                b"" => walk(b, records..next, l, false),
                b"zstd" if b[records..].starts_with(&STORED_ZSTD) => {
                    walk(b, records + 12..next, l, false);
                }
                _ => {}
            }
        }
        if top && b[at] == OP_FOOTER {
            l.footer = Some(at);
            let start = u64_at(b, at + 9).unwrap_or(0) as usize;
            l.summary = (start != 0 && start < at).then_some(start..at);
        }
        at = next;
    }
}

/// Lengths, offsets and sizes that break readers: zero, one, around 2³², 2⁴⁰, 2⁶³, 2⁶⁴, and
/// around the file's own size.
fn hostile(rng: &mut Rng, file: usize) -> u64 {
    const VALUES: &[u64] = &[
        0,
        1,
        8,
        0xFFFF_FFFF,
        1 << 32,
        1 << 40,
        i64::MAX as u64,
        u64::MAX - 8,
        u64::MAX,
    ];
    match rng.below(VALUES.len() + 3) {
        i if i < VALUES.len() => VALUES[i],
        i => (file as u64)
            .wrapping_add((i - VALUES.len()) as u64)
            .wrapping_sub(1),
    }
}

/// Writes `value`'s bytes at `at`, as far as the file goes.
fn put(b: &mut [u8], at: usize, value: &[u8]) {
    for (i, x) in value.iter().enumerate() {
        if let Some(y) = b.get_mut(at + i) {
            *y = *x;
        }
    }
}

/// A random range of at most `max` bytes inside `span`.
fn range_in(rng: &mut Rng, span: Range<usize>, max: usize) -> Range<usize> {
    let start = span.start + rng.below(span.len());
    start..(start + 1 + rng.below(max)).min(span.end)
}

/// `original` after 1 to 4 random edits chosen by `seed`.
fn mutate_recording(original: &[u8], seed: u64) -> Vec<u8> {
    let mut rng = Rng(seed);
    let l = layout(original);
    let mut b = original.to_vec();
    for _ in 0..1 + rng.below(4) {
        edit(&mut b, &l, &mut rng);
    }
    b
}

fn edit(b: &mut Vec<u8>, l: &Layout, rng: &mut Rng) {
    let len = b.len();
    let chunk = (!l.chunks.is_empty()).then(|| l.chunks[rng.below(l.chunks.len())].clone());
    match rng.below(10) {
        // Cut short anywhere.
        0 => b.truncate(rng.below(len + 1)),
        // Bits flipped in a few bytes anywhere.
        1 if len > 0 => {
            for i in range_in(rng, 0..len, 16) {
                b[i] ^= 1 << rng.below(8);
            }
        }
        // A run of zeros, 0xFF or random bytes over a chunk: its header, its compressed data
        // or the records inside it.
        2 | 3 => {
            let Some(c) = chunk else { return };
            let r = range_in(rng, c, 64);
            let fill = match rng.below(3) {
                0 => vec![0; r.len()],
                1 => vec![0xFF; r.len()],
                _ => rng.bytes(r.len()),
            };
            put(b, r.start, &fill);
        }
        // Garbage appended: random bytes, or a copy of part of the file (records again).
        4 => {
            if rng.below(2) == 0 {
                let n = 1 + rng.below(512);
                b.extend(rng.bytes(n));
            } else if len > 0 {
                let r = range_in(rng, 0..len, len);
                b.extend_from_within(r);
            }
        }
        // The summary zeroed, or the footer's offsets of it zeroed or made hostile.
        5 => match (&l.summary, l.footer) {
            (Some(s), _) if rng.below(2) == 0 => put(b, s.start, &vec![0; s.len()]),
            (_, Some(f)) => {
                let v = hostile(rng, len);
                put(b, f + 9 + 8 * rng.below(2), &v.to_le_bytes());
            }
            _ => {}
        },
        // A record's length made hostile (top-level, or inside a chunk).
        6 if !l.records.is_empty() => {
            let r = l.records[rng.below(l.records.len())];
            let v = hostile(rng, len);
            put(b, r + 1, &v.to_le_bytes());
        }
        // A chunk's uncompressed size, compression name length or records' length hostile.
        7 => {
            let Some(c) = chunk else { return };
            let content = c.start + 9;
            let v = hostile(rng, len);
            match rng.below(3) {
                0 => put(b, content + 16, &v.to_le_bytes()),
                1 => put(b, content + 28, &(v as u32).to_le_bytes()),
                _ => {
                    let n = u32_at(b, content + 28).unwrap_or(0);
                    put(b, content + 32 + n, &v.to_le_bytes());
                }
            }
        }
        // A hostile number anywhere: an index's offset or count, a string's length.
        8 if len > 0 => {
            let (at, v) = (rng.below(len), hostile(rng, len));
            if rng.below(2) == 0 {
                put(b, at, &v.to_le_bytes());
            } else {
                put(b, at, &(v as u32).to_le_bytes());
            }
        }
        // A part of the file copied over another.
        _ if len > 0 => {
            let from = range_in(rng, 0..len, 256);
            let to = rng.below(len);
            let copy = b[from].to_vec();
            put(b, to, &copy);
        }
        _ => {}
    }
}

/// A recording of [`PINGPONG`] run in lockstep for `duration` by `caravan launch`.
fn record_pingpong(tag: &str, duration: &str) -> Vec<u8> {
    let s = Scenario::new(tag, PINGPONG);
    let out = s.run(&["--duration", duration]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    std::fs::read(s.run_dirs().pop().unwrap().join("record.mcap")).unwrap()
}

/// `bytes` written again with `compression` in chunks of about `chunk` bytes, with its
/// attachments and metadata.
fn rewrite(bytes: &[u8], compression: Option<mcap::Compression>, chunk: u64) -> Vec<u8> {
    let mut out = std::io::Cursor::new(Vec::new());
    let options = mcap::WriteOptions::new()
        .compression(compression)
        .chunk_size(Some(chunk));
    let mut w = options.create(&mut out).unwrap();
    for m in mcap::MessageStream::new(bytes).unwrap() {
        w.write(&m.unwrap()).unwrap();
    }
    let summary = mcap::Summary::read(bytes).unwrap().unwrap();
    for index in &summary.attachment_indexes {
        w.attach(&mcap::read::attachment(bytes, index).unwrap())
            .unwrap();
    }
    for index in &summary.metadata_indexes {
        w.write_metadata(&mcap::read::metadata(bytes, index).unwrap())
            .unwrap();
    }
    w.finish().unwrap();
    drop(w);
    out.into_inner()
}

/// An uncompressed recording's chunks as zstd frames that store their records as they are
/// (one raw block), so that edits to the records reach the reader through the decompressor;
/// without a summary, as a recording cut short after its data.
fn stored_zstd(plain: &[u8]) -> Vec<u8> {
    let mut out = plain[..8].to_vec();
    let mut at = 8;
    while let Some(len) = u64_at(plain, at + 1) {
        let next = at + 9 + len as usize;
        match plain[at] {
            OP_CHUNK => {
                let content = &plain[at + 9..next];
                let n = u32_at(content, 28).unwrap();
                assert_eq!(n, 0, "the chunks are uncompressed");
                let records = &content[40..];
                let size = records.len();
                let mut frame = STORED_ZSTD.to_vec();
                frame.extend((size as u32).to_le_bytes());
                frame.extend(&((size as u32) << 3 | 1).to_le_bytes()[..3]);
                frame.extend(records);
                let mut chunk = content[..28].to_vec();
                chunk.extend(4u32.to_le_bytes());
                chunk.extend(b"zstd");
                chunk.extend((frame.len() as u64).to_le_bytes());
                chunk.extend(frame);
                out.push(OP_CHUNK);
                out.extend((chunk.len() as u64).to_le_bytes());
                out.extend(chunk);
            }
            // The data section's CRC no longer holds: 0, not checked.
            OP_DATA_END => {
                out.push(OP_DATA_END);
                out.extend(4u64.to_le_bytes());
                out.extend(0u32.to_le_bytes());
                break;
            }
            _ => out.extend(&plain[at..next]),
        }
        at = next;
    }
    out.push(OP_FOOTER);
    out.extend(20u64.to_le_bytes());
    out.extend([0; 20]);
    out.extend(mcap::MAGIC);
    out
}

/// The recordings the fuzz edits: a real one of 1 s (zstd, one chunk) and copies of it
/// uncompressed in chunks of 1 KiB, with lz4 in chunks of 4 KiB, and with stored zstd frames.
/// Each reads whole, with the same messages.
fn recordings() -> &'static [Vec<u8>] {
    static SEEDS: OnceLock<Vec<Vec<u8>>> = OnceLock::new();
    SEEDS.get_or_init(|| {
        let real = record_pingpong("fuzz-seed", "1s");
        let plain = rewrite(&real, None, 1024);
        let lz4 = rewrite(&real, Some(mcap::Compression::Lz4), 4096);
        let stored = stored_zstd(&plain);
        let seeds = vec![real, plain, lz4, stored];
        let count = |b: &[u8]| describe(b).unwrap()["messages"].as_u64().unwrap();
        for (i, s) in seeds.iter().enumerate() {
            assert!(count(s) > 10, "seed {i}");
            assert_eq!(count(s), count(&seeds[0]), "seed {i}");
            assert!(layout(s).records.len() > 10, "seed {i}");
        }
        seeds
    })
}

/// A file in the temporary directory, removed when dropped.
struct TempFile(PathBuf);

impl Drop for TempFile {
    fn drop(&mut self) {
        let _ = std::fs::remove_file(&self.0);
    }
}

/// What `caravan info`, `play` and `resim` read of the recording `bytes`, in this process;
/// each gives a value or an error.
fn read_as_the_commands_do(bytes: &[u8], file: &Path) {
    let _ = describe(bytes);
    std::fs::write(file, bytes).unwrap();
    let _ = read_recording(file, &[]);
    let _ = read_recording(file, &["demo/p*".into()]);
    if let Ok((text, _)) = attached_launch_file(file, bytes) {
        let at = workspace_root().join("launch/attached.toml");
        let _ = load_source(&at, Some(text), &[], &any_program, &|_| Vec::new());
    }
}

/// Inputs the fuzzing found: a summary whose channel counts overflow a u64 when summed
/// (`caravan info` added them unchecked), and a metadata index whose offset and length
/// overflow (the mcap crate adds them unchecked); both panicked.
#[test]
fn recordings_whose_summary_numbers_overflow_are_bad_input_to_info() {
    let seeds = recordings();
    let file = TempFile(
        std::env::temp_dir().join(format!("caravan-fuzz-overflow-{}.mcap", std::process::id())),
    );
    for (pick, seed) in [
        (15241006544738682866usize, 16685454973526671123u64),
        (8940219213943492806, 9647165503881495367),
    ] {
        let bytes = mutate_recording(&seeds[pick % seeds.len()], seed);
        read_as_the_commands_do(&bytes, &file.0);
    }
}

proptest! {
    // About 3 ms an input in a debug build, after a 1 s recording is made.
    #![proptest_config(config(4000))]

    #[test]
    fn fuzz_recording_readers_never_panic(pick in any::<usize>(), seed in any::<u64>()) {
        // One file for all cases: a million cases must not make a million files.
        thread_local!(static FILE: TempFile = TempFile(std::env::temp_dir()
            .join(format!("caravan-fuzz-{}.mcap", std::process::id()))));
        let seeds = recordings();
        let bytes = mutate_recording(&seeds[pick % seeds.len()], seed);
        let started = Instant::now();
        FILE.with(|f| read_as_the_commands_do(&bytes, &f.0));
        prop_assert!(started.elapsed() < BOUND, "{} B took {:?}", bytes.len(), started.elapsed());
    }
}

/// A recording cut short, and one with 64 bytes of 0xFF over its chunk's compressed data: the
/// commands refuse both as bad input (exit 2), naming the file, without a panic or a hang.
#[test]
fn a_truncated_or_corrupted_recording_is_bad_input_to_info_play_and_resim() {
    let s = Scenario::new("fuzz-bad", "");
    let bytes = record_pingpong("fuzz-bad-rec", "1s");
    let chunk = layout(&bytes).chunks[0].clone();
    assert!(chunk.len() > 300, "{chunk:?}");
    let mut corrupted = bytes.clone();
    corrupted[chunk.start + 100..chunk.start + 164].fill(0xFF);
    let runs = s.dir.join("runs");
    for (name, b) in [
        ("truncated.mcap", &bytes[..bytes.len() / 2]),
        ("corrupted.mcap", &corrupted[..]),
    ] {
        let file = s.dir.join(name);
        std::fs::write(&file, b).unwrap();
        let f = file.to_str().unwrap();
        for args in [
            vec!["info", f],
            vec!["play", f, "--group", "no-such-group-for-fuzz"],
            vec!["resim", f, "--node", "pong", "--quiet"],
        ] {
            let mut args = args;
            if args[0] == "resim" {
                args.extend(["--runs-dir", runs.to_str().unwrap()]);
            }
            let out = caravan(&args);
            let err = String::from_utf8_lossy(&out.stderr);
            assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
            assert!(!err.contains("panicked"), "{args:?}: {err}");
            assert!(err.contains(name), "{args:?}: {err}");
        }
    }
    assert!(!runs.exists(), "a rerun was started");
}

// ---------------------------------------------------------------------------------------------
// Hosts tables

/// Three hosts over QUIC with TLS (the certificates of tests/data/tls, relative to the file),
/// in realtime: one listens, two dial it, one may leave; a lease of its own.
const TLS_HOSTS: &str = r#"[group]
name = "fuzz-tls"
clock = "realtime"
host_lease = "2s"

[hosts.a]
listen = ["quic/127.0.0.1:7450"]
tls = { ca = "ca.pem", certificate = "host.pem", key = "host.key" }

[hosts.b]
connect = ["quic/127.0.0.1:7450"]
tls = { ca = "ca.pem", certificate = "fleet-a.pem", key = "fleet-a.key" }

[hosts.c]
connect = ["quic/127.0.0.1:7450", "quic/[::1]:7451"]
required = false
cpu_slowdown = 4.0
tls = { ca = "fleet-ca.pem", certificate = "fleet-c.pem", key = "fleet-c.key" }

[[process]]
name = "ping"
exec = "caravan-demo ping"
host = "a"
rate = "10Hz"

[[process]]
name = "pong"
exec = "caravan-demo pong"
host = "c"
on = "demo/ping"
"#;

/// The launch files with `[hosts]` tables, each with the path it is loaded as (includes and
/// tls files are found from there): the convoy on three machines with a host lease of its
/// own, the convoy on its WLAN, and [`TLS_HOSTS`].
fn hosts_files() -> Vec<(PathBuf, String)> {
    let root = workspace_root();
    let shipped = |p: &str| (root.join(p), std::fs::read_to_string(root.join(p)).unwrap());
    let (hosts_path, hosts) = shipped("launch/convoy/convoy-hosts.toml");
    let hosts = hosts.replacen("[args]", "[group]\nhost_lease = \"3s\"\n\n[args]", 1);
    let files = vec![
        (hosts_path, hosts),
        shipped("launch/convoy/convoy-wlan.toml"),
        (root.join("tests/data/tls/launch.toml"), TLS_HOSTS.into()),
    ];
    for (path, text) in &files {
        let lf = load_source(path, Some(text.clone()), &[], &any_program, &|_| Vec::new())
            .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        assert!(lf.hosts.len() >= 2, "{}", path.display());
        // The WLAN's hosts are simulated on one machine: it is not run with --host.
        if !path.ends_with("convoy-wlan.toml") {
            for name in lf.hosts.keys() {
                check_host(&lf, name).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
            }
        }
    }
    files
}

proptest! {
    // About 2.5 ms an input in a debug build (the convoy's includes are read each time).
    #![proptest_config(config(5000))]

    #[test]
    fn fuzz_hosts_tables_never_panic(pick in any::<usize>(), seed in any::<u64>()) {
        thread_local!(static FILES: Vec<(PathBuf, String)> = hosts_files());
        let (path, text) = FILES.with(|f| {
            let (path, text) = &f[pick % f.len()];
            (path.clone(), mutate(text, seed))
        });
        let started = Instant::now();
        if let Ok(lf) = load_source(&path, Some(text), &[], &any_program, &|_| Vec::new()) {
            for (name, spec) in &lf.hosts {
                let _ = check_host(&lf, name);
                let _ = session_config(spec, lf.group.host_lease);
            }
            let _ = check_host(&lf, "nohost");
        }
        prop_assert!(started.elapsed() < BOUND, "took {:?}", started.elapsed());
    }
}

// ---------------------------------------------------------------------------------------------
// Policy files

/// The shipped TD3 actors (one JSON line each), and the first of them pretty-printed, so that
/// the line edits reach its structure.
fn policies() -> Vec<String> {
    let dir = workspace_root().join("launch/uav/policies");
    let mut files: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|e| e == "json"))
        .map(|p| std::fs::read_to_string(p).unwrap())
        .collect();
    files.sort();
    assert!(!files.is_empty());
    let value: serde_json::Value = serde_json::from_str(&files[0]).unwrap();
    files.push(serde_json::to_string_pretty(&value).unwrap());
    for f in &files {
        assert_eq!(Mlp::parse(f, 6).unwrap().outputs(), 2);
    }
    files
}

proptest! {
    // About 13 ms an input in a debug build (each file is 100 kB).
    #![proptest_config(config(1000))]

    #[test]
    fn fuzz_policy_loader_never_panics(pick in any::<usize>(), seed in any::<u64>()) {
        thread_local!(static POLICIES: Vec<String> = policies());
        let text = POLICIES.with(|p| mutate(&p[pick % p.len()], seed));
        let started = Instant::now();
        if let Ok(mlp) = Mlp::parse(&text, 6) {
            // A network that loads acts, whatever its output's width.
            let _ = mlp.forward(&[0.5; 6]);
        }
        prop_assert!(started.elapsed() < BOUND, "took {:?}", started.elapsed());
    }
}

/// A weights file that is a device, a directory or absurdly large is refused at once, before
/// it is read.
#[test]
fn absurd_policy_files_are_refused() {
    let dir = std::env::temp_dir().join(format!("caravan-fuzz-policy-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let huge = dir.join("huge.json");
    // Sparse: no disk is used.
    let f = std::fs::File::create(&huge).unwrap();
    f.set_len(caravan::input::MAX_INPUT_BYTES + 1).unwrap();
    for (path, expected) in [
        (huge.as_path(), "more than the"),
        (Path::new("/dev/zero"), "not a regular file"),
        (dir.as_path(), "not a regular file"),
    ] {
        let started = Instant::now();
        let e = Mlp::read(path, 6).unwrap_err();
        assert!(e.contains(expected), "{}: {e}", path.display());
        assert!(
            started.elapsed() < Duration::from_secs(1),
            "{}",
            path.display()
        );
    }
    std::fs::remove_dir_all(&dir).unwrap();
}
