//! UDP on loopback. A payload larger than one datagram is split into fragments of at most
//! 60 KiB, sent back to back and reassembled in order into the receive buffer (no copy beyond
//! the kernel's). Loopback neither reorders nor drops datagrams as long as the receiving
//! socket's buffer holds a whole message, so both sockets ask for a buffer of twice the
//! payload; where the kernel grants less (`net.core.rmem_max` without privileges), the size is
//! reported as unsupported. A lost fragment ends the measurement with an error after a timeout.

use super::payload::{mark, read_mark};
use super::{ECHO_TIMEOUT, PONG_IDLE, Pair, Recorder, ready};
use anyhow::{Result, bail};
use std::io::ErrorKind;
use std::net::{SocketAddr, UdpSocket};
use std::os::fd::AsRawFd;
use std::time::Instant;

/// Largest datagram sent.
const FRAGMENT: usize = 60 * 1024;

/// The receive buffer a payload of `bytes` needs: every fragment costs its size plus the
/// kernel's per-packet overhead; twice the payload leaves room for both.
fn needed_buffer(bytes: usize) -> usize {
    (2 * bytes).max(256 * 1024)
}

/// Whether a socket here can get a receive buffer for `bytes`.
pub fn supports(bytes: usize) -> bool {
    UdpSocket::bind("127.0.0.1:0")
        .ok()
        .and_then(|s| grow_receive_buffer(&s, needed_buffer(bytes)).ok())
        .is_some_and(|granted| granted >= needed_buffer(bytes))
}

fn setsockopt_int(socket: &UdpSocket, option: libc::c_int, value: usize) -> bool {
    let value = value.min(i32::MAX as usize) as libc::c_int;
    // SAFETY: a valid socket and a pointer to an int of the given length.
    unsafe {
        libc::setsockopt(
            socket.as_raw_fd(),
            libc::SOL_SOCKET,
            option,
            (&value as *const libc::c_int).cast(),
            size_of::<libc::c_int>() as libc::socklen_t,
        ) == 0
    }
}

/// Asks for a receive buffer of `bytes` (beyond rmem_max where privileged); returns what the
/// kernel granted (it doubles the request for its bookkeeping and reports the doubled value).
fn grow_receive_buffer(socket: &UdpSocket, bytes: usize) -> Result<usize> {
    if !setsockopt_int(socket, libc::SO_RCVBUFFORCE, bytes) {
        setsockopt_int(socket, libc::SO_RCVBUF, bytes);
    }
    let mut value: libc::c_int = 0;
    let mut len = size_of::<libc::c_int>() as libc::socklen_t;
    // SAFETY: a valid socket and out-pointers of the right size.
    let rc = unsafe {
        libc::getsockopt(
            socket.as_raw_fd(),
            libc::SOL_SOCKET,
            libc::SO_RCVBUF,
            (&mut value as *mut libc::c_int).cast(),
            &mut len,
        )
    };
    if rc != 0 {
        bail!("getsockopt: {}", std::io::Error::last_os_error());
    }
    Ok(value as usize)
}

fn socket(bytes: usize) -> Result<UdpSocket> {
    let socket = UdpSocket::bind("127.0.0.1:0")?;
    grow_receive_buffer(&socket, needed_buffer(bytes))?;
    setsockopt_int(&socket, libc::SO_SNDBUF, needed_buffer(bytes));
    Ok(socket)
}

fn send(socket: &UdpSocket, buf: &[u8], to: SocketAddr) -> Result<()> {
    for chunk in buf.chunks(FRAGMENT) {
        let sent = socket.send_to(chunk, to)?;
        if sent != chunk.len() {
            bail!("sent {sent} of {} bytes", chunk.len());
        }
    }
    Ok(())
}

/// Receives one message of `buf.len()` bytes; returns its sender, or `None` for an empty
/// datagram (the stop signal).
fn receive(socket: &UdpSocket, buf: &mut [u8]) -> std::io::Result<Option<SocketAddr>> {
    let mut from = None;
    let mut offset = 0;
    while offset < buf.len() {
        let end = (offset + FRAGMENT).min(buf.len());
        let (n, addr) = socket.recv_from(&mut buf[offset..end])?;
        if n == 0 && offset == 0 {
            return Ok(None);
        }
        if n != end - offset {
            return Err(std::io::Error::new(
                ErrorKind::InvalidData,
                format!("fragment of {n} bytes, expected {}", end - offset),
            ));
        }
        from = Some(addr);
        offset = end;
    }
    Ok(from)
}

pub fn ping(pair: &Pair, rec: &mut Recorder) -> Result<()> {
    let socket = socket(pair.bytes)?;
    socket.set_read_timeout(Some(ECHO_TIMEOUT))?;
    let to: SocketAddr = format!("127.0.0.1:{}", pair.endpoint).parse()?;
    let mut buf = vec![0u8; pair.bytes];
    for seq in 0..rec.total() {
        let sent_at = Instant::now();
        mark(&mut buf, seq);
        send(&socket, &buf, to)?;
        match receive(&socket, &mut buf) {
            Ok(Some(_)) => {}
            Ok(None) => bail!("round {seq}: empty echo"),
            Err(e) => bail!("round {seq}: {e} (a fragment was lost?)"),
        }
        let rtt = sent_at.elapsed();
        let got = read_mark(&buf);
        if got != Some(seq) {
            bail!("echo of round {seq} came back as {got:?}");
        }
        rec.record(rtt);
    }
    // An empty datagram stops the echo side.
    socket.send_to(&[], to)?;
    Ok(())
}

pub fn pong(pair: &Pair) -> Result<()> {
    let socket = socket(pair.bytes)?;
    socket.set_read_timeout(Some(PONG_IDLE))?;
    ready(&socket.local_addr()?.port().to_string());
    let mut buf = vec![0u8; pair.bytes];
    while let Some(from) = receive(&socket, &mut buf)? {
        send(&socket, &buf, from)?;
    }
    Ok(())
}
