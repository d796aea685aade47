//! Containers: several nodes of one program in one process, stepped by one thread.
//!
//! In lockstep every node is a process that the scheduler wakes once per grant: the convoy's
//! five sensors cost five wake-ups a tick. Nodes of one program that the launch file puts in
//! one `container` run in one process instead (like ROS 2's component containers), each on a
//! stack of its own (a stackful coroutine). Where a node would sleep until its next grant it
//! *parks*, and the container's one thread sleeps in `poll(2)` on every member's grant
//! socket: grants that arrive together are stepped after one wake-up. Whenever the container
//! wakes, every parked member looks for its grant, so the scheduler wakes a container once for
//! a batch of grants to its members, not once per member.
//!
//! Each member stays a node of its own to the group: its name, params, ports, lockstep
//! grants, status and report row. What members share is the process: they start, fail and
//! stop together, and one member's step holds up the others' (they take turns on one core).

use crate::{Error, NodeIdentity};
use corosensei::{CoroutineResult, ScopedCoroutine, Yielder, stack::DefaultStack};
use serde::{Deserialize, Serialize};
use std::cell::Cell;
use std::time::{Duration, Instant};

/// Stack of each member, bytes: a process's main thread gets as much. Pages are committed only
/// when touched.
const STACK_BYTES: usize = 8 << 20;

/// One member of a container, as the launcher hands it over in
/// [`crate::env_vars::CONTAINER`] (a JSON array of these).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Member {
    /// The node's name in the group.
    pub node: String,
    /// Its params table (a JSON object).
    pub params: serde_json::Value,
    /// Its `rate` override, as written in the launch file.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rate: Option<String>,
    /// Its `on` override.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub on: Option<String>,
}

/// The identities of this process's members, if the launcher started it as a container: the
/// group's settings from the environment, each member's own name, params and trigger.
/// Members never spin: a member spinning for its grant would hold up the others.
pub fn members_from_env() -> Result<Option<Vec<NodeIdentity>>, Error> {
    let var = crate::env_vars::CONTAINER;
    let Some(text) = std::env::var(var).ok().filter(|t| !t.is_empty()) else {
        return Ok(None);
    };
    let members: Vec<Member> = serde_json::from_str(&text).map_err(|e| Error::Env {
        var,
        message: format!("not a list of members: {e}"),
    })?;
    if members.is_empty() {
        return Err(Error::Env {
            var,
            message: "names no member".into(),
        });
    }
    let base = NodeIdentity::from_env()?;
    if base.clock != crate::ClockMode::Lockstep {
        // A member's realtime loop sleeps in its own WaitSet and would never give the thread up.
        return Err(Error::Env {
            var,
            message: "containers step in lockstep only; in realtime the launcher starts each node as a process of its own".into(),
        });
    }
    Ok(Some(
        members
            .into_iter()
            .map(|m| NodeIdentity {
                name: m.node,
                params: m.params,
                rate_override: m.rate,
                on_override: m.on,
                spin: Duration::ZERO,
                ..base.clone()
            })
            .collect(),
    ))
}

/// Where a member waits: readable `fd`, or `deadline`.
struct Park {
    fd: i32,
    deadline: Instant,
}

/// How a member's [`park`] ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Unparked {
    /// SIGTERM or SIGINT came meanwhile.
    pub terminated: bool,
    /// Neither its `fd` nor its deadline: another member's wake-up, which may have brought
    /// this member's grant too (the scheduler wakes a container once per batch). Its `fd`
    /// holds no event to take.
    pub peeked: bool,
}

type Coro<'a> = ScopedCoroutine<'a, Unparked, Park, Result<(), Error>, DefaultStack>;
type MemberRef<'r> =
    corosensei::ScopedCoroutineRef<'r, Unparked, Park, Result<(), Error>, DefaultStack>;

thread_local! {
    /// The yielder of the member running now; null outside a container's member.
    static CURRENT: Cell<*const Yielder<Unparked, Park>> = const { Cell::new(std::ptr::null()) };
}

/// Inside a container's member: gives the thread to the other members until `fd` is readable,
/// `timeout` passed or another member's `fd` was readable (see [`Unparked::peeked`]). Outside
/// a container: `None`, and the caller waits as it would.
pub(crate) fn park(fd: i32, timeout: Duration) -> Option<Unparked> {
    let yielder = CURRENT.with(Cell::get);
    if yielder.is_null() {
        return None;
    }
    if timeout.is_zero() {
        return Some(Unparked {
            terminated: termination_requested(),
            peeked: false,
        });
    }
    // SAFETY: `CURRENT` is set only by a member's own body (below) to its yielder, which lives
    // on the member's stack for as long as the member runs, and this code runs on that stack.
    let y = unsafe { &*yielder };
    let unparked = y.suspend(Park {
        fd,
        deadline: Instant::now() + timeout,
    });
    // Other members ran meanwhile and set their own.
    CURRENT.with(|c| c.set(yielder));
    Some(unparked)
}

/// This process's id if the caller is a container's member (on its stack), else 0: what a
/// member's hello says, so that the scheduler wakes the container once per batch of grants.
pub(crate) fn id() -> u32 {
    if CURRENT.with(Cell::get).is_null() {
        0
    } else {
        std::process::id()
    }
}

fn termination_requested() -> bool {
    iceoryx2_bb_posix::signal::SignalHandler::termination_requested()
}

/// What a member runs: it joins the group and steps the node until the group stops.
pub type Body<'a> = Box<dyn FnOnce() -> Result<(), Error> + 'a>;

/// Runs `members` (each a node's name and the body that joins the group and steps it) on this
/// thread until all have returned. The first member to fail ends the container: the others
/// are unwound (their ports closed) and its name and error are returned.
pub fn run<'a>(members: Vec<(String, Body<'a>)>) -> Result<(), (String, Error)> {
    let mut names = Vec::new();
    let mut coroutines = Vec::new();
    for (name, body) in members {
        let stack = DefaultStack::new(STACK_BYTES)
            .map_err(|e| (name.clone(), Error::Lockstep(format!("member stack: {e}"))))?;
        names.push(name);
        coroutines.push(Coro::with_stack(
            stack,
            move |yielder: &Yielder<Unparked, Park>, _| {
                CURRENT.with(|c| c.set(yielder));
                body()
            },
        ));
    }
    in_scopes(coroutines, Vec::new(), |mut refs| {
        schedule(&names, &mut refs)
    })
}

/// Opens every coroutine's scope (each nested in the last) and runs `f` on them all.
fn in_scopes<'a, R>(
    mut rest: Vec<Coro<'a>>,
    refs: Vec<MemberRef<'_>>,
    f: impl for<'r> FnOnce(Vec<MemberRef<'r>>) -> R,
) -> R {
    match rest.pop() {
        None => {
            let mut refs = refs;
            refs.reverse();
            f(refs)
        }
        Some(coroutine) => coroutine.scope(move |r| {
            let mut refs = refs;
            refs.push(r);
            in_scopes(rest, refs, f)
        }),
    }
}

/// The container's loop: resume each member that can go on, then sleep until one can.
fn schedule(names: &[String], members: &mut [MemberRef<'_>]) -> Result<(), (String, Error)> {
    let mut parked: Vec<Option<Park>> = Vec::new();
    let mut live = vec![true; members.len()];
    let start = Unparked {
        terminated: false,
        peeked: false,
    };
    let mut ready: Vec<(usize, Unparked)> = (0..members.len()).map(|i| (i, start)).collect();
    parked.resize_with(members.len(), || None);
    loop {
        for &(i, unparked) in &ready {
            let result = members[i].as_mut().resume(unparked);
            CURRENT.with(|c| c.set(std::ptr::null()));
            match result {
                CoroutineResult::Yield(park) => parked[i] = Some(park),
                CoroutineResult::Return(Ok(())) => {
                    live[i] = false;
                    parked[i] = None;
                }
                CoroutineResult::Return(Err(e)) => return Err((names[i].clone(), e)),
            }
        }
        if !live.iter().any(|&l| l) {
            return Ok(());
        }
        let waiting: Vec<usize> = (0..members.len()).filter(|&i| live[i]).collect();
        let mut fds: Vec<libc::pollfd> = waiting
            .iter()
            .map(|&i| libc::pollfd {
                fd: parked[i].as_ref().map_or(-1, |p| p.fd),
                events: libc::POLLIN,
                revents: 0,
            })
            .collect();
        let now = Instant::now();
        let deadline = waiting
            .iter()
            .filter_map(|&i| parked[i].as_ref().map(|p| p.deadline))
            .min()
            .unwrap_or(now);
        let timeout_ms = deadline
            .saturating_duration_since(now)
            .as_micros()
            .div_ceil(1000)
            .min(i32::MAX as u128) as i32;
        // SAFETY: `fds` is a valid array of `fds.len()` pollfd for the call's duration.
        let n = unsafe { libc::poll(fds.as_mut_ptr(), fds.len() as libc::nfds_t, timeout_ms) };
        if n < 0 {
            let e = std::io::Error::last_os_error();
            if e.kind() != std::io::ErrorKind::Interrupted {
                return Err((
                    names[waiting[0]].clone(),
                    Error::Lockstep(format!("poll: {e}")),
                ));
            }
        }
        let terminated = termination_requested();
        let now = Instant::now();
        // A wake-up for one member may bring the others' grants: all look (`Unparked::peeked`).
        let woken = fds.iter().any(|fd| fd.revents != 0);
        ready = waiting
            .iter()
            .zip(&fds)
            .filter_map(|(&i, fd)| {
                let own = fd.revents != 0 || parked[i].as_ref().is_none_or(|p| p.deadline <= now);
                (terminated || woken || own).then_some((
                    i,
                    Unparked {
                        terminated,
                        peeked: !own && !terminated,
                    },
                ))
            })
            .collect();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn members_round_trip_as_the_launcher_writes_them() {
        let m = Member {
            node: "sensor-1".into(),
            params: serde_json::json!({"robot": 1}),
            rate: Some("50Hz".into()),
            on: None,
        };
        let text = serde_json::to_string(&vec![m.clone()]).unwrap();
        assert_eq!(
            text,
            r#"[{"node":"sensor-1","params":{"robot":1},"rate":"50Hz"}]"#
        );
        let back: Vec<Member> = serde_json::from_str(&text).unwrap();
        assert_eq!(back, vec![m]);
    }

    /// Two members parked on pipes: each goes on when its own pipe is written, peeks (is
    /// resumed as `peeked`, and parks again) when the other's is, and the container ends when
    /// both have returned.
    #[test]
    fn members_take_turns_on_their_own_wake_ups_and_peek_at_the_others() {
        let pipe = || {
            let mut fds = [0; 2];
            // SAFETY: `fds` has room for the two descriptors pipe(2) writes.
            assert_eq!(unsafe { libc::pipe(fds.as_mut_ptr()) }, 0);
            fds
        };
        let (a, b) = (pipe(), pipe());
        let log = std::cell::RefCell::new(Vec::new());
        let member = |name: &'static str, read: i32, write_other: i32| {
            let log = &log;
            Box::new(move || {
                for round in 0..2 {
                    log.borrow_mut().push(format!("{name} waits {round}"));
                    loop {
                        let unparked = park(read, Duration::from_secs(10)).unwrap();
                        assert!(!unparked.terminated);
                        if !unparked.peeked {
                            break;
                        }
                        log.borrow_mut().push(format!("{name} peeks {round}"));
                    }
                    let mut byte = 0u8;
                    // SAFETY: reads one byte into `byte` from a pipe we own.
                    unsafe { libc::read(read, (&mut byte as *mut u8).cast(), 1) };
                    log.borrow_mut().push(format!("{name} woke {round}"));
                    // SAFETY: writes one byte from a live local to a pipe we own.
                    unsafe { libc::write(write_other, (&byte as *const u8).cast(), 1) };
                }
                Ok(())
            }) as Body<'_>
        };
        // b starts the exchange: a byte in a's pipe.
        // SAFETY: as above.
        unsafe { libc::write(a[1], [7u8].as_ptr().cast(), 1) };
        run(vec![
            ("a".into(), member("a", a[0], b[1])),
            ("b".into(), member("b", b[0], a[1])),
        ])
        .unwrap();
        assert_eq!(
            *log.borrow(),
            [
                "a waits 0",
                "b waits 0",
                "a woke 0",
                "a waits 1",
                "b peeks 0",
                "a peeks 1",
                "b woke 0",
                "b waits 1",
                "a woke 1",
                "b peeks 1",
                "b woke 1"
            ]
        );
        assert_eq!(park(0, Duration::from_secs(1)), None, "outside a container");
    }

    #[test]
    fn the_first_member_to_fail_ends_the_container_naming_it() {
        let ok = Box::new(|| -> Result<(), Error> {
            park(-1, Duration::from_millis(1));
            Ok(())
        });
        let bad = Box::new(|| -> Result<(), Error> { Err(Error::Lockstep("broken".into())) });
        let (name, e) = run(vec![("ok".into(), ok), ("bad".into(), bad)]).unwrap_err();
        assert_eq!(name, "bad");
        assert!(e.to_string().contains("broken"), "{e}");
    }
}
