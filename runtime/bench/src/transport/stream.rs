//! Stream sockets: a Unix domain socket and TCP on loopback (TCP_NODELAY), blocking reads.
//! The whole payload goes through the kernel each way; the echo writes back what it read.

use super::payload::{mark, read_mark};
use super::{ECHO_TIMEOUT, PONG_IDLE, Pair, Recorder, ready};
use anyhow::{Context, Result, bail};
use std::io::{ErrorKind, Read, Write};
use std::net::{TcpListener, TcpStream};
use std::os::unix::net::{UnixListener, UnixStream};
use std::time::Instant;

pub fn ping_uds(pair: &Pair, rec: &mut Recorder) -> Result<()> {
    let path = pair.temp_path("sock");
    let stream = UnixStream::connect(&path)
        .with_context(|| format!("cannot connect to {}", path.display()))?;
    stream.set_read_timeout(Some(ECHO_TIMEOUT))?;
    ping(stream, pair.bytes, rec)
}

pub fn pong_uds(pair: &Pair) -> Result<()> {
    let path = pair.temp_path("sock");
    let _ = std::fs::remove_file(&path);
    let listener =
        UnixListener::bind(&path).with_context(|| format!("cannot bind {}", path.display()))?;
    ready("");
    let (stream, _) = listener.accept()?;
    stream.set_read_timeout(Some(PONG_IDLE))?;
    pong(stream, pair.bytes)
}

pub fn ping_tcp(pair: &Pair, rec: &mut Recorder) -> Result<()> {
    let stream = TcpStream::connect(("127.0.0.1", pair.endpoint.parse::<u16>()?))?;
    stream.set_nodelay(true)?;
    stream.set_read_timeout(Some(ECHO_TIMEOUT))?;
    ping(stream, pair.bytes, rec)
}

pub fn pong_tcp(pair: &Pair) -> Result<()> {
    let listener = TcpListener::bind("127.0.0.1:0")?;
    ready(&listener.local_addr()?.port().to_string());
    let (stream, _) = listener.accept()?;
    stream.set_nodelay(true)?;
    stream.set_read_timeout(Some(PONG_IDLE))?;
    pong(stream, pair.bytes)
}

/// Writes the whole payload, reads the whole echo. Closing the connection stops the echo side.
fn ping(mut stream: impl Read + Write, bytes: usize, rec: &mut Recorder) -> Result<()> {
    let mut buf = vec![0u8; bytes];
    for seq in 0..rec.total() {
        let sent_at = Instant::now();
        mark(&mut buf, seq);
        stream.write_all(&buf)?;
        stream.read_exact(&mut buf)?;
        let rtt = sent_at.elapsed();
        let got = read_mark(&buf);
        if got != Some(seq) {
            bail!("echo of round {seq} came back as {got:?}");
        }
        rec.record(rtt);
    }
    Ok(())
}

fn pong(mut stream: impl Read + Write, bytes: usize) -> Result<()> {
    let mut buf = vec![0u8; bytes];
    loop {
        match stream.read_exact(&mut buf) {
            Ok(()) => stream.write_all(&buf)?,
            Err(e) if e.kind() == ErrorKind::UnexpectedEof => return Ok(()),
            Err(e) => return Err(e.into()),
        }
    }
}
