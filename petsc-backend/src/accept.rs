//! The driver's connection, found among whatever else connects to the builder's port. Any local
//! process (and, with `host` set, any machine that reaches it) can connect; none may take the
//! driver's place or hold the build up. So no read ever blocks: one `poll` waits on the listener
//! and on every connection that has not greeted yet, each connection has GREETING_SECONDS from
//! its accept to send its whole greeting line (however it trickles in), and one is dropped as
//! soon as it shows it is not the driver's. The driver's connection is taken the moment its
//! greeting is complete, however many others are open or how slowly they send.

use crate::messages::{Greeting, PROTOCOL};
use std::io::{Cursor, ErrorKind, Read};
use std::net::{SocketAddr, TcpListener, TcpStream};
use std::os::fd::AsRawFd;
use std::time::{Duration, Instant};

/// How long a connection may take, from its accept, to send its whole greeting: the driver
/// sends it at once.
pub(crate) const GREETING_SECONDS: u64 = 10;

/// Longest greeting line (the driver's is about 150 bytes).
const GREETING_BYTES: usize = 4096;

/// Connections waiting to greet at one time. A flood beyond it drops the longest waiting first:
/// the driver greets within a round trip of its accept, so it is never the longest waiting, and
/// the builder's open files stay well under the usual limit of 1024.
const MOST_PENDING: usize = 256;

/// Connections accepted between two looks at those already open, so that a flood of new ones
/// does not keep the builder from reading the driver's greeting.
const ACCEPTS_PER_ROUND: usize = 32;

/// Dropped connections named one by one (in `--timings` and the timeout's message); beyond them
/// only counted, so a flood fills neither.
const NAMED_DROPS: usize = 8;

/// The driver's connection: its stream and what it sent after its greeting line (nothing, as
/// a rule: its next line is the factor's answer).
pub(crate) type DriverStream = std::io::Chain<Cursor<Vec<u8>>, TcpStream>;

/// Why a connection to the builder's port was dropped before it proved to be the driver's.
#[derive(Debug, thiserror::Error)]
enum Dropped {
    #[error("{0}")]
    Io(#[from] std::io::Error),
    #[error("it closed without a greeting")]
    Closed,
    #[error("no greeting within {0} s")]
    Silent(f64),
    #[error("a greeting not finished within {0} s ({1} bytes)")]
    Slow(f64, usize),
    #[error("a greeting over {GREETING_BYTES} bytes")]
    TooLong,
    #[error("a greeting that is not the driver's")]
    NotTheDriver,
    #[error("a wrong token")]
    WrongToken,
    #[error("protocol {0} where the builder speaks {PROTOCOL}")]
    Protocol(serde_json::Value),
    #[error("crowded out by {MOST_PENDING} newer connections")]
    Crowded,
}

/// A connection that has not greeted yet.
struct Pending {
    stream: TcpStream,
    peer: SocketAddr,
    received: Vec<u8>,
    deadline: Instant,
}

/// What the connection's greeting, complete or not, says so far.
enum Greeted {
    /// Not a whole line yet.
    Partial,
    /// The driver's: what it sent after the line.
    Driver(Vec<u8>),
    Refused(Dropped),
}

/// The connections dropped so far: their number and the first few, with why.
#[derive(Default)]
pub(crate) struct Drops {
    pub count: usize,
    pub named: Vec<String>,
}

impl Drops {
    fn record(&mut self, peer: SocketAddr, why: &Dropped) {
        self.count += 1;
        if self.named.len() < NAMED_DROPS {
            phases::note(|| format!("a connection from {peer} was dropped: {why}"));
            self.named.push(format!("{peer}: {why}"));
        }
    }

    /// "" if none was dropped, else " (N other connections dropped: ...)".
    pub fn summary(&self) -> String {
        if self.count == 0 {
            return String::new();
        }
        let more = self.count - self.named.len();
        let more = if more > 0 { format!("; {more} more") } else { String::new() };
        format!(" ({} other connections dropped: {}{more})", self.count, self.named.join("; "))
    }
}

/// The listener and the connections waiting to greet on it.
pub(crate) struct Acceptor<'a> {
    listener: &'a TcpListener,
    token: &'a str,
    pending: Vec<Pending>,
    /// GREETING_SECONDS (shorter in the unit tests).
    greeting_time: Duration,
    pub drops: Drops,
}

impl<'a> Acceptor<'a> {
    pub fn new(listener: &'a TcpListener, token: &'a str) -> std::io::Result<Self> {
        listener.set_nonblocking(true)?;
        let greeting_time = Duration::from_secs(GREETING_SECONDS);
        Ok(Self { listener, token, pending: Vec::new(), greeting_time, drops: Drops::default() })
    }

    /// Waits until `until` at most: the driver's connection (blocking again, and what it sent
    /// after its greeting) once it has greeted, else None. Only a failure of the listener
    /// itself is an error.
    pub fn wait(&mut self, until: Instant) -> std::io::Result<Option<DriverStream>> {
        loop {
            let (listener_ready, ready) = self.poll(until)?;
            for i in ready.into_iter().rev() {
                if let Some(driver) = self.read_greeting(i)? {
                    return Ok(Some(driver));
                }
            }
            if listener_ready && let Some(driver) = self.accept_some()? {
                return Ok(Some(driver));
            }
            self.drop_late(Instant::now());
            if Instant::now() >= until {
                return Ok(None);
            }
        }
    }

    /// Waits for the listener or a pending connection to be readable, a greeting time to end or
    /// `until`: whether the listener is ready, and the indices of the ready connections.
    fn poll(&self, until: Instant) -> std::io::Result<(bool, Vec<usize>)> {
        let wake = self.pending.iter().map(|p| p.deadline).fold(until, Instant::min);
        // rounded up: a wake-up a little early would only poll again
        let millis = wake.saturating_duration_since(Instant::now()).as_micros().div_ceil(1000);
        let timeout = i32::try_from(millis).unwrap_or(i32::MAX);
        let mut fds: Vec<libc::pollfd> = std::iter::once(self.listener.as_raw_fd())
            .chain(self.pending.iter().map(|p| p.stream.as_raw_fd()))
            .map(|fd| libc::pollfd { fd, events: libc::POLLIN, revents: 0 })
            .collect();
        // SAFETY: `fds` is a valid array of fds.len() pollfd entries for the call's duration
        let n = unsafe { libc::poll(fds.as_mut_ptr(), fds.len() as libc::nfds_t, timeout) };
        if n < 0 {
            let e = std::io::Error::last_os_error();
            return if e.kind() == ErrorKind::Interrupted { Ok((false, Vec::new())) } else { Err(e) };
        }
        let ready = |f: &libc::pollfd| f.revents != 0;
        let connections = fds[1..].iter().enumerate().filter(|(_, f)| ready(f)).map(|(i, _)| i).collect();
        Ok((ready(&fds[0]), connections))
    }

    /// Accepts what the listener holds, a round's worth at most, and reads each one's greeting
    /// at once (the driver's is usually there already).
    fn accept_some(&mut self) -> std::io::Result<Option<DriverStream>> {
        for _ in 0..ACCEPTS_PER_ROUND {
            let (stream, peer) = match self.listener.accept() {
                Ok(accepted) => accepted,
                Err(e) if matches!(e.kind(), ErrorKind::WouldBlock | ErrorKind::Interrupted) => return Ok(None),
                Err(e) if is_transient(&e) => {
                    // out of files (a flood): the longest waiting makes room
                    self.crowd_out();
                    return Ok(None);
                }
                Err(e) => return Err(e),
            };
            if let Err(e) = stream.set_nonblocking(true) {
                self.drops.record(peer, &Dropped::Io(e));
                continue;
            }
            if self.pending.len() >= MOST_PENDING {
                self.crowd_out();
            }
            let deadline = Instant::now() + self.greeting_time;
            self.pending.push(Pending { stream, peer, received: Vec::new(), deadline });
            if let Some(driver) = self.read_greeting(self.pending.len() - 1)? {
                return Ok(Some(driver));
            }
        }
        Ok(None)
    }

    /// Drops the connection that has waited longest.
    fn crowd_out(&mut self) {
        if !self.pending.is_empty() {
            let oldest = self.pending.remove(0);
            self.drops.record(oldest.peer, &Dropped::Crowded);
        }
    }

    /// Reads what connection `i` sent: the driver's stream once its greeting is whole; a
    /// connection that proves not to be the driver's is dropped.
    fn read_greeting(&mut self, i: usize) -> std::io::Result<Option<DriverStream>> {
        let p = &mut self.pending[i];
        let greeted = match receive(p) {
            Ok(()) => judge(&p.received, self.token),
            Err(why) => Greeted::Refused(why),
        };
        match greeted {
            Greeted::Partial => Ok(None),
            Greeted::Refused(why) => {
                let p = self.pending.remove(i);
                self.drops.record(p.peer, &why);
                Ok(None)
            }
            Greeted::Driver(rest) => {
                let p = self.pending.remove(i);
                p.stream.set_nonblocking(false)?;
                p.stream.set_nodelay(true).ok();
                Ok(Some(Cursor::new(rest).chain(p.stream)))
            }
        }
    }

    /// Drops every connection whose greeting time has ended.
    fn drop_late(&mut self, now: Instant) {
        let (late, waiting): (Vec<_>, Vec<_>) =
            std::mem::take(&mut self.pending).into_iter().partition(|p| now >= p.deadline);
        self.pending = waiting;
        for p in late {
            let seconds = self.greeting_time.as_secs_f64();
            let why =
                if p.received.is_empty() { Dropped::Silent(seconds) } else { Dropped::Slow(seconds, p.received.len()) };
            self.drops.record(p.peer, &why);
        }
    }
}

/// An accept failure that says the builder is short of files or the peer left, not that the
/// listener is broken.
fn is_transient(e: &std::io::Error) -> bool {
    let code = e.raw_os_error().unwrap_or(0);
    [libc::EMFILE, libc::ENFILE, libc::ENOBUFS, libc::ENOMEM, libc::ECONNABORTED, libc::EPROTO].contains(&code)
        || e.kind() == ErrorKind::ConnectionAborted
}

/// Appends what the connection has sent, without waiting: Err when it closed or sent too much.
fn receive(p: &mut Pending) -> Result<(), Dropped> {
    let mut buffer = [0u8; 1024];
    loop {
        match p.stream.read(&mut buffer) {
            Ok(0) => return Err(Dropped::Closed),
            Ok(k) => {
                p.received.extend_from_slice(&buffer[..k]);
                if p.received.contains(&b'\n') {
                    return Ok(());
                }
                if p.received.len() > GREETING_BYTES {
                    return Err(Dropped::TooLong);
                }
            }
            Err(e) if e.kind() == ErrorKind::WouldBlock => return Ok(()),
            Err(e) if e.kind() == ErrorKind::Interrupted => {}
            Err(e) => return Err(e.into()),
        }
    }
}

/// What `received` says: a whole greeting line with the job's token and the protocol is the
/// driver's.
fn judge(received: &[u8], token: &str) -> Greeted {
    let Some(end) = received.iter().position(|&b| b == b'\n') else { return Greeted::Partial };
    if end >= GREETING_BYTES {
        return Greeted::Refused(Dropped::TooLong);
    }
    let Ok(hello) = serde_json::from_slice::<Greeting>(&received[..end]) else {
        return Greeted::Refused(Dropped::NotTheDriver);
    };
    if !same(hello.hello.as_bytes(), token.as_bytes()) {
        return Greeted::Refused(Dropped::WrongToken);
    }
    if hello.protocol.as_u64() != Some(PROTOCOL) {
        return Greeted::Refused(Dropped::Protocol(hello.protocol));
    }
    Greeted::Driver(received[end + 1..].to_vec())
}

/// Whether two tokens are equal, in a time that does not tell how much of a guess was right.
fn same(a: &[u8], b: &[u8]) -> bool {
    a.len() == b.len() && a.iter().zip(b).fold(0u8, |acc, (x, y)| acc | (x ^ y)) == 0
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::{BufRead, BufReader, Write};
    use std::thread;

    const TOKEN: &str = "0123456789abcdef";

    fn greeting(token: &str) -> String {
        format!("{{\"hello\": \"{token}\", \"protocol\": {PROTOCOL}, \"ranks\": 2}}\n")
    }

    fn listener() -> (TcpListener, SocketAddr) {
        let l = TcpListener::bind(("127.0.0.1", 0)).unwrap();
        let a = l.local_addr().unwrap();
        (l, a)
    }

    /// The driver: connects after `after`, greets, then sends `then`.
    fn driver(address: SocketAddr, after: Duration, then: &'static str) -> thread::JoinHandle<TcpStream> {
        thread::spawn(move || {
            thread::sleep(after);
            let mut s = TcpStream::connect(address).unwrap();
            s.write_all(format!("{}{then}", greeting(TOKEN)).as_bytes()).unwrap();
            s
        })
    }

    fn wait_long(acceptor: &mut Acceptor<'_>, seconds: u64) -> Option<DriverStream> {
        acceptor.wait(Instant::now() + Duration::from_secs(seconds)).unwrap()
    }

    #[test]
    fn the_driver_is_taken_at_once_beside_silent_and_trickling_connections() {
        let (l, address) = listener();
        let mut acceptor = Acceptor::new(&l, TOKEN).unwrap();
        let silent: Vec<TcpStream> = (0..6).map(|_| TcpStream::connect(address).unwrap()).collect();
        let mut trickle = TcpStream::connect(address).unwrap();
        let stop = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
        let stop_trickle = stop.clone();
        let trickler = thread::spawn(move || {
            while !stop_trickle.load(std::sync::atomic::Ordering::SeqCst) {
                if trickle.write_all(b"{").is_err() {
                    break;
                }
                thread::sleep(Duration::from_millis(20));
            }
        });
        let began = Instant::now();
        let d = driver(address, Duration::from_millis(300), "{\"ok\": true}\n");
        let stream = wait_long(&mut acceptor, 20).expect("the driver");
        let waited = began.elapsed();
        stop.store(true, std::sync::atomic::Ordering::SeqCst);
        trickler.join().unwrap();
        assert!(waited < Duration::from_millis(1300), "{waited:?}");
        // what the driver sent after its greeting is kept for the next read
        let mut line = String::new();
        BufReader::new(stream).read_line(&mut line).unwrap();
        assert_eq!(line, "{\"ok\": true}\n");
        drop((silent, d.join()));
    }

    #[test]
    fn impostors_are_dropped_each_with_why() {
        let (l, address) = listener();
        let mut acceptor = Acceptor::new(&l, TOKEN).unwrap();
        acceptor.greeting_time = Duration::from_millis(300);
        let mut open = Vec::new();
        for sent in [
            "junk\n".to_string(),
            greeting("fedcba9876543210"),
            greeting("short"),
            greeting(TOKEN).replace(&format!(": {PROTOCOL},"), ": 1,"),
            "x".repeat(GREETING_BYTES + 10),
            "{\"hel".to_string(),
            String::new(),
        ] {
            let mut s = TcpStream::connect(address).unwrap();
            s.write_all(sent.as_bytes()).unwrap();
            open.push(s);
        }
        drop(TcpStream::connect(address).unwrap());
        assert!(acceptor.wait(Instant::now() + Duration::from_millis(600)).unwrap().is_none());
        let why = acceptor.drops.named.join("\n");
        for expected in [
            "a greeting that is not the driver's",
            "a wrong token",
            "protocol 1 where the builder speaks",
            &format!("a greeting over {GREETING_BYTES} bytes"),
            "a greeting not finished within 0.3 s (5 bytes)",
            "no greeting within 0.3 s",
            "it closed without a greeting",
        ] {
            assert!(why.contains(expected), "{expected} not in:\n{why}");
        }
        assert_eq!(acceptor.drops.count, 8, "{why}");
        assert!(acceptor.pending.is_empty());
        let summary = acceptor.drops.summary();
        assert!(summary.starts_with(" (8 other connections dropped: ") && !summary.contains("more"), "{summary}");
    }

    #[test]
    fn a_flood_of_silent_connections_does_not_crowd_out_the_driver() {
        let (l, address) = listener();
        let mut acceptor = Acceptor::new(&l, TOKEN).unwrap();
        // connected while the acceptor runs (the listener's backlog alone holds 128)
        let flooder = thread::spawn(move || {
            let connect = |n| (0..n).map(|_| TcpStream::connect(address).unwrap()).collect::<Vec<_>>();
            let before = connect(MOST_PENDING + 40);
            let d = driver(address, Duration::ZERO, "").join().unwrap();
            (before, connect(40), d)
        });
        assert!(wait_long(&mut acceptor, 20).is_some());
        let kept = flooder.join().unwrap();
        assert!(acceptor.pending.len() <= MOST_PENDING);
        let summary = acceptor.drops.summary();
        assert!(summary.contains("crowded out by") && summary.contains("more)"), "{summary}");
        drop(kept);
    }
}
