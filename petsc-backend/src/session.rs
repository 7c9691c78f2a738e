//! One run of the driver (`driver.py`) under MPI, from its launch to its last answer: the job
//! folder with the stiffness in PETSc's binary format, the launcher's process, and the TCP
//! connection rank 0 opens back to the builder. Requests go one at a time (a JSON line, then
//! little-endian doubles); a failed request is an error naming what the driver reported.

use crate::PetscBackend;
use crate::accept::{Acceptor, DriverStream};
use crate::error::{BackendError, Result};
use crate::heartbeat::{self, Heartbeats, Trouble};
use crate::messages::{self, Answer, Factored, Request};
use crate::process_group::LocalRanks;
use crate::{job_folder, petsc_binary, process_group};
use faer::sparse::SparseColMat;
use faer::{MatMut, MatRef};
use std::io::{BufRead, BufReader, Read, Write};
use std::net::{TcpListener, TcpStream};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, ExitStatus, Stdio};
use std::sync::Mutex;
use std::time::{Duration, Instant};

/// The driver, shipped inside the builder and written into each job folder: builder and driver
/// always speak the same protocol.
pub(super) const DRIVER: &str = include_str!("driver.py");

/// The builder's sparse matrices (`linalg::sparse::Sparse`, which builds on this module).
type Sparse = SparseColMat<usize, f64>;

struct Connection {
    reader: BufReader<DriverStream>,
    writer: std::io::BufWriter<TcpStream>,
}

/// What the driver reported when its factor was ready.
#[derive(Clone, Debug)]
pub struct Started {
    pub ranks: usize,
    pub rows_per_rank: Vec<usize>,
    pub factor_entries: f64,
    pub load_seconds: f64,
    pub partition_seconds: f64,
    pub factor_seconds: f64,
}

pub struct Session {
    connection: Mutex<Connection>,
    child: Mutex<Child>,
    /// The launcher's process group: it and every local rank.
    group: i32,
    launched: String,
    folder: PathBuf,
    keep_folder: bool,
    rows: usize,
    /// The ranks' heartbeat files in the job folder.
    heartbeats: Heartbeats,
    /// The ranks on this machine, seen while they run.
    ranks: LocalRanks,
    /// The first failure of a request that could not return an error (a solve inside the
    /// `SpdSolve` trait): reported by `health`.
    failure: Mutex<Option<BackendError>>,
    pub started: Started,
}

fn io_error(what: &str) -> impl Fn(std::io::Error) -> BackendError + '_ {
    move |e| BackendError::unavailable(format!("{what}: {e}")).caused_by(e)
}

/// How often a wait for the driver looks at the launcher and the ranks.
const WATCH_INTERVAL: Duration = Duration::from_secs(1);

/// How often a wait for the driver's connection looks at the launcher and the ranks: often
/// enough to see a rank that fails as it starts (before its heartbeat watcher does), rarely
/// enough that the look (a walk of /proc) costs little.
const CONNECT_WATCH_INTERVAL: Duration = Duration::from_millis(100);

/// The launcher's report (the driver's standard error), for a message: its first lines (mpirun
/// puts its headline there, "not enough slots"), then its last; or that it said nothing.
fn tail(path: &Path, lines: usize) -> String {
    let text = std::fs::read_to_string(path).unwrap_or_default();
    let all: Vec<&str> = text.lines().filter(|l| !l.trim().is_empty()).collect();
    if all.is_empty() {
        return "(nothing on its standard error)".to_string();
    }
    if all.len() <= 2 * lines {
        return all.join("\n");
    }
    format!("{}\n...\n{}", all[..lines].join("\n"), all[all.len() - lines..].join("\n"))
}

/// What a wait for the driver watches: the launcher (ended?) and its process group (a rank
/// stopped?), and where the launcher's report is.
struct Watch<'a> {
    child: &'a Mutex<Child>,
    group: i32,
    heartbeats: &'a Heartbeats,
    ranks: &'a LocalRanks,
    stderr: PathBuf,
    launched: String,
}

impl Watch<'_> {
    /// The launcher's exit status once it has ended, waited for `wait` at most.
    fn launcher_status(&self, wait: Duration) -> Option<ExitStatus> {
        let deadline = Instant::now() + wait;
        loop {
            let status = self.child.lock().ok().and_then(|mut c| c.try_wait().ok().flatten());
            if status.is_some() || Instant::now() >= deadline {
                return status;
            }
            std::thread::sleep(Duration::from_millis(50));
        }
    }

    /// What the launcher says of the job's end: the rank that failed where its report names it,
    /// its own status (or that it still runs), and its report.
    fn report(&self, status: Option<ExitStatus>) -> String {
        let text = std::fs::read_to_string(&self.stderr).unwrap_or_default();
        let rank = failed_rank(&text).map_or_else(String::new, |r| format!("{r}; "));
        let ended =
            status.map_or_else(|| "the launcher still runs".to_string(), |s| format!("the launcher ended ({s})"));
        format!("{rank}{ended}; `{}` reported:\n{}", self.launched, tail(&self.stderr, 12))
    }

    /// What the launcher says once the job has ended, waited for a few seconds (mpirun names
    /// the rank that died only as it ends), or, where a rank is gone and the launcher runs on
    /// without it a second later, that rank.
    fn closing_report(&self) -> String {
        let deadline = Instant::now() + Duration::from_secs(10);
        let mut gone: Option<(String, Instant)> = None;
        loop {
            if let Some(status) = self.launcher_status(Duration::ZERO) {
                return self.report(Some(status));
            }
            if gone.is_none() {
                gone = self.rank_trouble().filter(|t| t.ended).map(|t| (t.why, Instant::now()));
            }
            let given_up = gone.as_ref().is_some_and(|(_, seen)| seen.elapsed() >= Duration::from_secs(1))
                && !self.launcher_names_a_failed_rank();
            if given_up || Instant::now() >= deadline {
                let why = gone.map_or_else(String::new, |(why, _)| format!("{why}; "));
                return format!("{why}{}", self.report(None));
            }
            std::thread::sleep(Duration::from_millis(50));
        }
    }

    /// Whether the launcher's report names a rank that failed: mpirun, which then ends the
    /// other ranks and itself (a second or more under load).
    fn launcher_names_a_failed_rank(&self) -> bool {
        failed_rank(&std::fs::read_to_string(&self.stderr).unwrap_or_default()).is_some()
    }

    /// The launcher's status once a rank has ended: a launcher that noticed ends within moments,
    /// one that says nothing of it is taken to run on after a second.
    fn status_after_a_rank_ended(&self) -> Option<ExitStatus> {
        let status = self.launcher_status(Duration::from_secs(1));
        if status.is_none() && self.launcher_names_a_failed_rank() {
            return self.launcher_status(Duration::from_secs(4));
        }
        status
    }

    /// What the ranks tell of the job: a local rank the builder saw that is gone (while its
    /// launcher runs on, the other ranks would wait for it forever), else what a heartbeat
    /// tells (ranks on other nodes, which neither the launcher's exit nor the local processes
    /// show).
    fn rank_trouble(&self) -> Option<Trouble> {
        if let Some((pid, rank)) = self.ranks.ended(self.group) {
            let why = format!("rank {rank} (process {pid}) ended while the job ran (it failed or was killed)");
            return Some(Trouble { why, ended: true });
        }
        self.heartbeats.check()
    }

    /// Err when the launcher has ended or a rank is stopped or gone, naming which.
    fn check(&self, waiting_for: &str) -> Result<()> {
        process_group::park_if_interrupted();
        if let Some(status) = self.launcher_status(Duration::ZERO) {
            let text = std::fs::read_to_string(&self.stderr).unwrap_or_default();
            let rank = failed_rank(&text).map_or_else(String::new, |r| format!("{r}; "));
            return Err(BackendError::unavailable(format!(
                "{rank}the launcher ended ({status}) while the builder waited for {waiting_for}; `{}` reported:\n{}",
                self.launched,
                tail(&self.stderr, 12)
            )));
        }
        if let Some((pid, rank, cmdline)) = process_group::stopped_member(self.group) {
            let who = rank.map_or_else(|| "a process of the job".to_string(), |r| format!("rank {r}"));
            return Err(BackendError::unavailable(format!(
                "{who} (process {pid}: {cmdline}) is stopped (SIGSTOP, a debugger) while the builder waited for \
                 {waiting_for}; the job was ended"
            )));
        }
        let Some(trouble) = self.rank_trouble() else { return Ok(()) };
        // a launcher that notices a rank's end ends within moments, and names how the rank ended
        let report =
            if trouble.ended { format!("; {}", self.report(self.status_after_a_rank_ended())) } else { String::new() };
        Err(BackendError::unavailable(format!(
            "{} while the builder waited for {waiting_for}; the job was ended{report}",
            trouble.why
        )))
    }
}

/// The line of the launcher's report that names the rank that failed, in a sentence: mpirun's
/// own ("noticed that process rank 1 ... exited on signal 9"), MPI_Abort's, the driver's, or
/// mpirun's "Process name: [[job,1],rank]" with the "Exit code:" after it.
fn failed_rank(report: &str) -> Option<String> {
    let lines: Vec<&str> = report.lines().map(str::trim).collect();
    let named = ["noticed that process rank", "MPI_ABORT was invoked on rank", "driver rank"];
    if let Some(line) = lines.iter().find(|l| named.iter().any(|n| l.contains(n))) {
        return Some(format!("a rank failed: {line}"));
    }
    let at = lines.iter().position(|l| l.starts_with("Process name:"))?;
    let rank = lines[at].rsplit(',').next()?.trim_end_matches(']').trim();
    let code = lines.get(at + 1).and_then(|l| l.strip_prefix("Exit code:")).map(str::trim)?;
    Some(format!("rank {rank} failed: it exited with code {code}"))
}

impl Session {
    /// Launch the driver on `backend.ranks` ranks and have it load, partition and factor `k`.
    pub fn start(backend: &PetscBackend, k: &Sparse, what: &str) -> Result<Self> {
        let base = backend.job_folder.clone().unwrap_or_else(std::env::temp_dir);
        let folder = job_folder::create(&base)?;
        if backend.keep_job_folder {
            job_folder::mark_kept(&folder)?;
        }
        let started = phases::phase(format!("PETSc back-end: {what}"), || Self::launch(backend, k, what, &folder));
        match started {
            Ok(session) => Ok(session),
            Err(e) => {
                if !backend.keep_job_folder {
                    job_folder::remove(&folder);
                }
                Err(e)
            }
        }
    }

    fn launch(backend: &PetscBackend, k: &Sparse, what: &str, folder: &Path) -> Result<Self> {
        let driver = folder.join("driver.py");
        job_folder::write_private(&driver, DRIVER)?;
        phases::phase("job files written", || petsc_binary::write_symmetric(&folder.join("stiffness.bin"), k))?;
        let (listener, port) = listen(backend)?;
        let token = job_folder::random_hex(32)?;
        let job_path = write_job(backend, folder, port, &token)?;
        let (program, arguments) = backend.command(&driver, &job_path);
        let stderr_path = folder.join("driver.err");
        let stdout = job_folder::private_file(&folder.join("driver.out"))?;
        let stderr = job_folder::private_file(&stderr_path)?;
        let launched = format!("{program} {}", arguments.join(" "));
        phases::note(|| format!("launched: {launched}"));
        let mut command = launcher_command(&program, &arguments, stdout, stderr);
        let child = command.spawn().map_err(|e| {
            BackendError::unavailable(format!(
                "could not start `{program}`: {e}; install OpenMPI (mpirun) or name the launcher \
                 (reduction.backend.launcher, --launcher)"
            ))
            .caused_by(e)
        })?;
        let group = child.id() as i32;
        process_group::register(group, folder, backend.keep_job_folder);
        let child = Mutex::new(child);
        let heartbeats = Heartbeats::new(folder, heartbeat::SILENCE);
        let ranks = LocalRanks::default();
        let watch = Watch {
            child: &child,
            group,
            heartbeats: &heartbeats,
            ranks: &ranks,
            stderr: stderr_path.clone(),
            launched: launched.clone(),
        };
        let connected = Self::connect(backend, listener, port, &token, &watch, what);
        drop(watch);
        let (connection, started) = match connected {
            Ok(c) => c,
            Err(e) => {
                process_group::kill_group(group);
                if let Ok(mut c) = child.lock() {
                    c.wait().ok();
                }
                process_group::unregister(group);
                return Err(e);
            }
        };
        Ok(Self {
            connection: Mutex::new(connection),
            child,
            group,
            launched,
            folder: folder.to_path_buf(),
            keep_folder: backend.keep_job_folder,
            rows: k.nrows(),
            heartbeats,
            ranks,
            failure: Mutex::new(None),
            started,
        })
    }

    /// Waits for the driver's connection and its factor. Other connections to the port are read
    /// side by side with it and dropped (accept.rs), so none can take the driver's place or hold
    /// the builder up; the launcher and the ranks are looked at all the while, so a job that
    /// failed is reported as such at once, not as a driver that never connected.
    fn connect(
        backend: &PetscBackend,
        listener: TcpListener,
        port: u16,
        token: &str,
        watch: &Watch<'_>,
        what: &str,
    ) -> Result<(Connection, Started)> {
        let stream = Self::accept_driver(backend, listener, port, token, watch)?;
        let writer = stream.get_ref().1.try_clone().map_err(io_error("the driver's connection"))?;
        // from here on a read waits in WATCH_INTERVAL slices, looking at the ranks between them
        writer.set_read_timeout(Some(WATCH_INTERVAL)).map_err(io_error("the driver's connection"))?;
        let mut connection = Connection {
            reader: BufReader::with_capacity(1 << 20, stream),
            writer: std::io::BufWriter::with_capacity(1 << 20, writer),
        };
        let answer = phases::phase("driver: load, partition and factor", || {
            read_line(&mut connection, watch, "the driver's factor")
        })?;
        let factored: Factored = parsed(&answer)?;
        if !factored.ok {
            let reason = messages::reason(&factored.error).to_string();
            return Err(BackendError::NotFactored { what: what.to_string(), reason });
        }
        let Some(figures) = factored.figures else { return Err(not_the_protocol("its figures missing", &answer)) };
        let started = Started {
            ranks: figures.ranks,
            rows_per_rank: figures.rows_per_rank,
            factor_entries: figures.factor_entries,
            load_seconds: figures.seconds.load,
            partition_seconds: figures.seconds.partition,
            factor_seconds: figures.seconds.factor,
        };
        let s = started.clone();
        phases::note(move || {
            format!(
                "{} ranks, rows per rank {:?}, MUMPS factor {:.3e} entries; load {:.1} s, partition {:.1} s, factor {:.1} s",
                s.ranks, s.rows_per_rank, s.factor_entries, s.load_seconds, s.partition_seconds, s.factor_seconds
            )
        });
        Ok((connection, started))
    }

    /// The driver's stream once it has greeted, within the connect timeout, while the launcher
    /// runs and no rank has stopped or ended. The listener is closed on return: no one else can
    /// connect once the driver has.
    fn accept_driver(
        backend: &PetscBackend,
        listener: TcpListener,
        port: u16,
        token: &str,
        watch: &Watch<'_>,
    ) -> Result<DriverStream> {
        let mut acceptor = Acceptor::new(&listener, token).map_err(io_error("listening"))?;
        let began = Instant::now();
        let deadline = began + Duration::from_secs_f64(backend.connect_timeout_seconds);
        loop {
            let slice_end = (Instant::now() + CONNECT_WATCH_INTERVAL).min(deadline);
            if let Some(stream) = acceptor.wait(slice_end).map_err(io_error("accepting the driver's connection"))? {
                return Ok(stream);
            }
            watch.check("the driver to connect")?;
            if Instant::now() >= deadline {
                return Err(BackendError::unavailable(format!(
                    "the driver did not connect to {}:{port} within {} s{} (reduction.backend.host must be an \
                     address the ranks reach the builder at; --connect-timeout or reduction.backend.connect_timeout \
                     sets the wait); `{}` reported:\n{}",
                    backend.host,
                    backend.connect_timeout_seconds,
                    acceptor.drops.summary(),
                    watch.launched,
                    tail(&watch.stderr, 12)
                )));
            }
            phases::step(|| {
                format!(
                    "waiting for the PETSc driver to connect: {:.0} s of {:.0}",
                    began.elapsed().as_secs_f64(),
                    backend.connect_timeout_seconds
                )
            });
        }
    }

    /// Rows of the factored matrix.
    pub fn rows(&self) -> usize {
        self.rows
    }

    /// One request: `header` (its "doubles" added), the blocks' columns in order; the answer's
    /// header and doubles. An answer with "ok": false is the error.
    fn request(&self, header: Request, blocks: &[MatRef<'_, f64>]) -> Result<(Answer, Vec<f64>)> {
        let mut c = self.connection.lock().map_err(|_| BackendError::unavailable("a lost lock on the connection"))?;
        let what = format!("the request {}", header.name());
        let line =
            serde_json::to_string(&header).map_err(|e| BackendError::request(format!("{what}: {e}")).caused_by(e))?;
        let send = |c: &mut Connection| -> std::io::Result<()> {
            c.writer.write_all(line.as_bytes())?;
            c.writer.write_all(b"\n")?;
            for b in blocks {
                for j in 0..b.ncols() {
                    for v in b.col(j).iter() {
                        c.writer.write_all(&v.to_le_bytes())?;
                    }
                }
            }
            c.writer.flush()
        };
        send(&mut c).map_err(|e| self.lost(&what, e))?;
        let watch = Watch {
            child: &self.child,
            group: self.group,
            heartbeats: &self.heartbeats,
            ranks: &self.ranks,
            stderr: self.folder.join("driver.err"),
            launched: self.launched.clone(),
        };
        let line = read_line(&mut c, &watch, &format!("the answer to {what}"))?;
        let answer: Answer = parsed(&line)?;
        let bytes = read_payload(&mut c, 8 * answer.doubles, &watch, &what)?;
        if !answer.ok {
            return Err(BackendError::request(format!(
                "the PETSc back-end failed {what}: {}",
                messages::reason(&answer.error)
            )));
        }
        let values = bytes.chunks_exact(8).map(|b| f64::from_le_bytes(b.try_into().unwrap_or([0; 8]))).collect();
        Ok((answer, values))
    }

    fn lost(&self, what: &str, e: std::io::Error) -> BackendError {
        process_group::park_if_interrupted();
        BackendError::unavailable(format!(
            "the connection broke during {what} ({e}); the driver reported:\n{}",
            tail(&self.folder.join("driver.err"), 12)
        ))
        .caused_by(e)
    }

    /// x = K^-1 b for every column, through the distributed factor.
    pub fn solve(&self, mut rhs: MatMut<'_, f64>) -> Result<()> {
        if rhs.ncols() == 0 {
            return Ok(());
        }
        let request = Request::Solve { columns: rhs.ncols(), doubles: rhs.nrows() * rhs.ncols() };
        let (_, x) = self.request(request, &[rhs.as_ref()])?;
        let n = rhs.nrows();
        if x.len() != n * rhs.ncols() {
            return Err(BackendError::request(format!(
                "the PETSc back-end returned {} values for {n} x {}",
                x.len(),
                rhs.ncols()
            )));
        }
        for j in 0..rhs.ncols() {
            for i in 0..n {
                rhs[(i, j)] = x[j * n + i];
            }
        }
        Ok(())
    }

    /// As `solve`, for callers that cannot return an error: a failure fills the columns with NaN
    /// and is kept for `health`, and every solve after it is NaN at once.
    pub fn solve_or_nan(&self, mut rhs: MatMut<'_, f64>) {
        // after a failure the job is gone or ending: no further request waits for it
        if self.failure.lock().map_or(true, |f| f.is_some()) {
            rhs.fill(f64::NAN);
            return;
        }
        if let Err(e) = self.solve(rhs.as_mut()) {
            rhs.fill(f64::NAN);
            if let Ok(mut failure) = self.failure.lock() {
                failure.get_or_insert(e);
            }
        }
    }

    /// The first failed solve's error, if one failed: the back-end's own (a rank stopped, the
    /// connection lost) or the numbers'.
    pub fn health(&self) -> Result<()> {
        match self.failure.lock().ok().and_then(|f| f.clone()) {
            Some(failure) => Err(failure),
            None => Ok(()),
        }
    }

    /// Peak resident memory of each rank so far, MiB.
    pub fn peak_memory(&self) -> Result<Vec<f64>> {
        let (answer, _) = self.request(Request::Stats { doubles: 0 }, &[])?;
        Ok(answer.peak_mib)
    }
}

/// A listener for the driver's connection at the address the ranks reach the builder at, and its port.
fn listen(backend: &PetscBackend) -> Result<(TcpListener, u16)> {
    let address = backend.listen_address();
    let listener = TcpListener::bind((address, 0)).map_err(|e| {
        BackendError::unavailable(format!(
            "cannot listen at {address} (reduction.backend.host: the address of this machine the ranks reach \
                 the builder at): {e}"
        ))
        .caused_by(e)
    })?;
    let port = listener.local_addr().map_err(io_error("opening a port"))?.port();
    Ok((listener, port))
}

/// `job.json`: where the driver connects back to, the token it greets with, the matrix and the
/// partitioner.
fn write_job(backend: &PetscBackend, folder: &Path, port: u16, token: &str) -> Result<PathBuf> {
    let job = messages::Job {
        host: &backend.host,
        port,
        token,
        stiffness: "stiffness.bin",
        partitioner: &backend.partitioner,
    };
    let job_path = folder.join("job.json");
    let text = serde_json::to_string(&job)
        .map_err(|e| BackendError::unavailable(format!("the job file: {e}")).caused_by(e))?;
    job_folder::write_private(&job_path, &text)?;
    Ok(job_path)
}

/// The launcher's command line with its output to the job folder's files.
fn launcher_command(program: &str, arguments: &[String], stdout: std::fs::File, stderr: std::fs::File) -> Command {
    let mut command = Command::new(program);
    command.args(arguments).stdin(Stdio::null()).stdout(stdout).stderr(stderr);
    // its own process group, so that the builder ends the launcher and every rank it forked
    // together, and a Ctrl-C reaches the builder only (process_group.rs)
    std::os::unix::process::CommandExt::process_group(&mut command, 0);
    // idle ranks wait in the kernel instead of spinning a core each (rank 0 spun at 83 %
    // while the builder computed)
    command.env("OMPI_MCA_mpi_yield_when_idle", "1");
    // SAFETY: geteuid only reads the process's user id
    if unsafe { libc::geteuid() } == 0 {
        // OpenMPI refuses root without both (containers and CI machines run as root)
        for v in ["OMPI_ALLOW_RUN_AS_ROOT", "OMPI_ALLOW_RUN_AS_ROOT_CONFIRM"] {
            if std::env::var_os(v).is_none() {
                command.env(v, "1");
            }
        }
    }
    command
}

fn timed_out(e: &std::io::Error) -> bool {
    matches!(e.kind(), std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut)
}

/// The next JSON line from the driver, however long it computes, as long as the launcher runs
/// and no rank is stopped.
fn read_line(c: &mut Connection, watch: &Watch<'_>, waiting_for: &str) -> Result<Vec<u8>> {
    let mut line = Vec::new();
    loop {
        // read_until keeps what it read before a timeout in `line`: the next call goes on
        match c.reader.read_until(b'\n', &mut line) {
            Ok(0) => {
                process_group::park_if_interrupted();
                return Err(BackendError::unavailable(format!(
                    "the driver closed its connection while the builder waited for {waiting_for}; {}",
                    watch.closing_report()
                )));
            }
            Ok(_) if line.ends_with(b"\n") => break,
            Ok(_) => {}
            Err(e) if timed_out(&e) => watch.check(waiting_for)?,
            Err(e) => {
                process_group::park_if_interrupted();
                return Err(io_error("reading the driver's answer")(e));
            }
        }
    }
    Ok(line)
}

/// A line of the driver's as the message it must be.
fn parsed<'a, T: serde::Deserialize<'a>>(line: &'a [u8]) -> Result<T> {
    serde_json::from_slice(line).map_err(|e| not_the_protocol(&e.to_string(), line).caused_by(e))
}

fn not_the_protocol(why: &str, line: &[u8]) -> BackendError {
    BackendError::unavailable(format!(
        "an answer that is not the protocol's ({why}): {}",
        String::from_utf8_lossy(line)
    ))
}

/// `count` bytes of an answer's payload, read as `read_line` reads.
fn read_payload(c: &mut Connection, count: usize, watch: &Watch<'_>, what: &str) -> Result<Vec<u8>> {
    let mut bytes = vec![0u8; count];
    let mut got = 0;
    while got < count {
        match c.reader.read(&mut bytes[got..]) {
            Ok(0) => {
                process_group::park_if_interrupted();
                return Err(BackendError::unavailable(format!(
                    "the driver closed its connection mid-answer to {what}; {}",
                    watch.closing_report()
                )));
            }
            Ok(k) => got += k,
            Err(e) if timed_out(&e) => watch.check(&format!("the answer to {what}"))?,
            Err(e) => {
                process_group::park_if_interrupted();
                return Err(io_error("reading the driver's answer")(e));
            }
        }
    }
    Ok(bytes)
}

impl Drop for Session {
    fn drop(&mut self) {
        let mut answered = false;
        if let Ok(mut c) = self.connection.lock() {
            let quit = serde_json::to_string(&Request::Quit).map_err(std::io::Error::other).and_then(|line| {
                c.writer.write_all(line.as_bytes())?;
                c.writer.write_all(b"\n")?;
                c.writer.flush()
            });
            if quit.is_ok() {
                let mut line = String::new();
                answered = c.reader.read_line(&mut line).is_ok_and(|n| n > 0);
            }
        }
        // a job that answered its quit ends by itself; one that did not (a rank stopped, the
        // connection broken) is ended at once
        if let Ok(mut child) = self.child.lock()
            && answered
        {
            let deadline = Instant::now() + Duration::from_secs(30);
            while matches!(child.try_wait(), Ok(None)) && Instant::now() < deadline {
                std::thread::sleep(Duration::from_millis(20));
            }
        }
        // whatever of the job is left (a rank that did not follow the launcher out)
        process_group::kill_group(self.group);
        if let Ok(mut child) = self.child.lock() {
            child.wait().ok();
        }
        process_group::unregister(self.group);
        if !self.keep_folder {
            job_folder::remove(&self.folder);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::failed_rank;

    #[test]
    fn the_failed_rank_is_found_in_the_launchers_report() {
        let signal =
            "----\nmpirun noticed that process rank 1 with PID 0 on node vm exited on signal 9 (Killed).\n----";
        assert_eq!(
            failed_rank(signal).as_deref(),
            Some(
                "a rank failed: mpirun noticed that process rank 1 with PID 0 on node vm exited on signal 9 (Killed)."
            )
        );
        let code = "The first process to do so was:\n\n  Process name: [[14536,1],1]\n  Exit code:    3\n";
        assert_eq!(failed_rank(code).as_deref(), Some("rank 1 failed: it exited with code 3"));
        assert_eq!(failed_rank("not enough slots available"), None);
    }
}
