"""The distributed back-end's driver: runs under MPI (mpirun -n N python3 driver.py JOB.json),
holds the mounted or shifted stiffness factored by MUMPS across the ranks, and serves the
builder's requests over one TCP connection from rank 0: blocks of solves, MUMPS's multiple
right-hand sides in one pass through the factor. Everything else stays in the builder: the FE
model, the mass products, and the eigen-solves, whose block Lanczos drives these block solves
(the same method, the same Krylov space shared by the whole and the held problem, and the same
order of operations as in process). Only the stiffness (a PETSc binary file in the job folder,
read by rank 0 and distributed by PETSc) and dense blocks of vectors cross to the ranks.

Rows keep PETSc's contiguous distribution unless `partitioner` names a MatPartitioning
(ptscotch, parmetis) of the stiffness's graph: MUMPS orders and maps the factor itself, and
only the blocks' scatters follow the rows. Each request is a JSON line, then the little-endian doubles it announces;
each answer too. The builder writes this file into the job folder from its own copy, so driver
and builder always match."""

import json
import os
import resource
import socket
import sys
import time
import traceback


# The heartbeat watcher (heartbeat.rs in the builder reads its files): run as its own Python,
# exec'd from a fork of each rank before MPI starts, so that it is no MPI process and its
# command line does not pass for a rank's. Every second it rewrites heartbeat-<host>-<pid>:
# rank, host, PID, the rank's state (stopped: /proc's T or t), a counter. When the rank is
# gone (the watcher re-parented) it writes a last beat, "ended", within a fifth of a second:
# a launcher that keeps running after a rank died (srun without --kill-on-bad-exit, mpirun
# with --enable-recovery) leaves the other ranks waiting for it, and only this beat tells.
WATCHER = r"""
import os, sys, time
folder, parent, rank, host = sys.argv[1], int(sys.argv[2]), sys.argv[3], sys.argv[4]
path = os.path.join(folder, "heartbeat-%s-%d" % (host, parent))
count = 0

def beat(state):
    line = "%s %s %d %s %d\n" % (rank, host, parent, state, count)
    try:
        fd = os.open(path + ".tmp", os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o600)
        os.write(fd, line.encode())
        os.close(fd)
        os.replace(path + ".tmp", path)
    except OSError:
        sys.exit(0)

while os.getppid() == parent:
    try:
        with open("/proc/%d/stat" % parent) as f:
            state = f.read().rpartition(")")[2].split()[0]
    except OSError:
        break
    count += 1
    beat("stopped" if state in "Tt" else "running")
    for _ in range(5):
        if os.getppid() != parent:
            break
        time.sleep(0.2)
count += 1
beat("ended")
"""


def start_heartbeat(folder):
    rank_name = next((os.environ[v] for v in ("OMPI_COMM_WORLD_RANK", "PMIX_RANK", "PMI_RANK", "SLURM_PROCID")
                      if v in os.environ), "?")
    parent = os.getpid()
    if os.fork() != 0:
        return
    try:
        null = os.open(os.devnull, os.O_RDWR)
        for fd in (0, 1, 2):
            os.dup2(null, fd)
        os.execv(sys.executable, [sys.executable, "-c", WATCHER, folder, str(parent), rank_name,
                                  socket.gethostname()])
    finally:
        os._exit(0)


if __name__ == "__main__" and len(sys.argv) == 2 and sys.argv[1] != "--probe":
    start_heartbeat(os.path.dirname(os.path.abspath(sys.argv[1])))


def debian_paths():
    """Debian's petsc4py finds itself through /usr/lib/petsc, a link only the -dev package
    makes: without it, PETSC_DIR names the install."""
    import glob

    for variable, link, pattern in [
        ("PETSC_DIR", "/usr/lib/petsc", "/usr/lib/petscdir/petsc*/*-linux-gnu-real"),
    ]:
        if os.environ.get(variable) or os.path.isdir(link):
            continue
        found = sorted(glob.glob(pattern))
        if found:
            os.environ[variable] = found[-1]
            packages = os.path.join(found[-1], "lib/python3/dist-packages")
            if packages not in sys.path:
                sys.path.append(packages)


debian_paths()
import petsc4py  # noqa: E402

petsc4py.init(sys.argv[:1])
from mpi4py import MPI  # noqa: E402
from petsc4py import PETSc  # noqa: E402
import numpy  # noqa: E402 -- petsc4py's own dependency

PROTOCOL = 2
comm = MPI.COMM_WORLD
rank = comm.Get_rank()
size = comm.Get_size()


class Failure(Exception):
    """A request that cannot be met: its message goes back to the builder."""


def peak_mib():
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def idle():
    """Waits, asleep, until every rank has got here: the other ranks wait for rank 0's next
    request while the builder computes, and MPI's own wait (even with yield_when_idle) spins a
    core each, which the builder's threads need (2.4e5 DoF, 2 ranks on 2 cores: the builder's
    orthogonalisation 13.9 s beside spinning ranks, 5.0 s beside one rank). A non-blocking
    barrier polled every 2 ms costs nothing beside a solve's tenths of a second."""
    if size == 1:
        return
    request = comm.Ibarrier()
    while not request.Test():
        time.sleep(0.002)


class Channel:
    """Rank 0's connection to the builder; the other ranks receive each request by broadcast."""

    def __init__(self, host, port, token):
        self.sock = None
        if rank == 0:
            self.sock = socket.create_connection((host, port), timeout=600)
            self.sock.settimeout(None)
            self.sock.sendall((json.dumps({"hello": token, "protocol": PROTOCOL, "ranks": size}) + "\n").encode())
            self.reader = self.sock.makefile("rb")

    def receive(self):
        """The next request (header, payload as a float array on rank 0, None elsewhere)."""
        header = None
        payload = None
        if rank == 0:
            line = self.reader.readline()
            header = json.loads(line) if line else {"op": "quit"}
            count = int(header.get("doubles", 0))
            payload = memoryview(self._read_exact(8 * count)).cast("d")
        idle()
        header = comm.bcast(header, root=0)
        return header, payload

    def _read_exact(self, n):
        buf = bytearray(n)
        view = memoryview(buf)
        got = 0
        while got < n:
            k = self.reader.readinto(view[got:])
            if not k:
                raise Failure("the builder closed the connection mid-request")
            got += k
        return buf

    def answer(self, header, doubles=None):
        if rank != 0:
            return
        header = dict(header)
        data = b""
        if doubles is not None:
            data = bytes(doubles)
            header["doubles"] = len(data) // 8
        self.sock.sendall((json.dumps(header) + "\n").encode() + data)


def load(path):
    viewer = PETSc.Viewer().createBinary(path, "r", comm=PETSc.COMM_WORLD)
    a = PETSc.Mat().create(comm=PETSc.COMM_WORLD)
    a.setType("aij")
    a.load(viewer)
    viewer.destroy()
    return a


class Layout:
    """Where each row lives: `rows` the original rows (the builder's numbering) this rank owns,
    in the order of its part of the distributed vectors and dense blocks. Rank 0 knows every
    rank's rows, and moves whole blocks of columns to and from the ranks with one MPI
    Scatterv/Gatherv each (not a scatter per column)."""

    def __init__(self, n, rows):
        self.n = n
        self.rows = rows
        self.local = rows.getLocalSize()
        everyone = comm.gather(numpy.asarray(rows.getIndices(), dtype=numpy.int64), root=0)
        if rank == 0:
            self.parts = everyone
            self.counts = [len(r) for r in everyone]
            # contiguous rows in order (no repartitioning): slices instead of index lists
            offsets = numpy.cumsum([0] + self.counts)
            self.contiguous = all(numpy.array_equal(r, numpy.arange(offsets[i], offsets[i + 1]))
                                  for i, r in enumerate(everyone))

    def spread_block(self, payload, count):
        """A column-major n x count block from rank 0 (None elsewhere): this rank's rows, as a
        local x count array."""
        received = numpy.empty((count, self.local))
        send = None
        if rank == 0:
            block = numpy.frombuffer(payload, dtype=float).reshape(count, self.n)
            if self.contiguous:
                ordered = block
            else:
                ordered = numpy.concatenate([block[:, r] for r in self.parts], axis=1)
            # each rank's part: its rows of every column, column after column
            send = numpy.concatenate([numpy.ascontiguousarray(part).ravel()
                                      for part in numpy.split(ordered, numpy.cumsum(self.counts)[:-1], axis=1)])
            counts = [c * count for c in self.counts]
            comm.Scatterv([send, counts, MPI.DOUBLE], received, root=0)
        else:
            comm.Scatterv(None, received, root=0)
        return received.T

    def gather_block(self, local):
        """This rank's local x count array: on rank 0 the n x count block column-major as bytes
        (None elsewhere)."""
        count = local.shape[1]
        mine = numpy.ascontiguousarray(local.T)
        if rank != 0:
            comm.Gatherv(mine, None, root=0)
            return None
        received = numpy.empty(self.n * count)
        comm.Gatherv(mine, [received, [c * count for c in self.counts], MPI.DOUBLE], root=0)
        parts = numpy.split(received, numpy.cumsum([c * count for c in self.counts])[:-1])
        ordered = numpy.concatenate([part.reshape(count, c) for part, c in zip(parts, self.counts)], axis=1)
        if self.contiguous:
            return ordered.tobytes()
        block = numpy.empty((count, self.n))
        start = 0
        for r, c in zip(self.parts, self.counts):
            block[:, r] = ordered[:, start:start + c]
            start += c
        return block.tobytes()


def natural_layout(a):
    start, end = a.getOwnershipRange()
    rows = PETSc.IS().createStride(end - start, first=start, step=1, comm=PETSc.COMM_WORLD)
    return Layout(a.getSize()[0], rows)


def partitioned(a, partitioner):
    """`a` redistributed by PETSc's partitioning of its graph: the matrix in the new
    distribution and its layout."""
    n = a.getSize()[0]
    if size == 1 or partitioner == "current":
        return a, natural_layout(a)
    part = PETSc.MatPartitioning().create(comm=PETSc.COMM_WORLD)
    part.setAdjacency(a)
    part.setType(partitioner)
    part.setFromOptions()
    target = PETSc.IS()
    part.apply(target)
    rows = target.buildTwoSided()
    rows.sort()
    part.destroy()
    b = a.createSubMatrix(rows, rows)
    return b, Layout(n, rows)


class Factor:
    """The stiffness in PETSc's distribution, factored by MUMPS (LDL^T, its inertia checked)."""

    def __init__(self, path, partitioner):
        began = time.perf_counter()
        natural = load(path)
        self.load_seconds = time.perf_counter() - began
        began = time.perf_counter()
        self.k, self.layout = partitioned(natural, partitioner)
        if self.k is not natural:
            natural.destroy()
        self.partition_seconds = time.perf_counter() - began
        self.k.setOption(PETSc.Mat.Option.SYMMETRIC, True)
        self.ksp = PETSc.KSP().create(comm=PETSc.COMM_WORLD)
        self.ksp.setOperators(self.k)
        self.ksp.setType("preonly")
        pc = self.ksp.getPC()
        pc.setType("cholesky")
        pc.setFactorSolverType("mumps")
        pc.setFactorSetUpSolverType()
        f = pc.getFactorMatrix()
        # inertia (negative pivots) and null pivots reported: a matrix that is not positive
        # definite is refused, as the in-process Cholesky refuses it
        f.setMumpsIcntl(13, 1)
        f.setMumpsIcntl(24, 1)
        # the fill-reducing order: METIS on the matrix's graph (MUMPS's sequential analysis,
        # the graph only; Debian's MUMPS has no parallel ordering: INFOG(1) = -38 with
        # ICNTL(28) = 2); PETSc options (PETSC_OPTIONS) may choose another
        f.setMumpsIcntl(28, 1)
        f.setMumpsIcntl(7, 5)
        self.ksp.setFromOptions()
        began = time.perf_counter()
        try:
            self.ksp.setUp()
        except PETSc.Error:
            pass
        self.factor_seconds = time.perf_counter() - began
        info = f.getMumpsInfog(1)
        if info < 0:
            raise Failure("MUMPS failed to factor the matrix (INFOG(1) = %d, INFOG(2) = %d)" % (info, f.getMumpsInfog(2)))
        negative = f.getMumpsInfog(12)
        null = f.getMumpsInfog(28)
        if negative > 0 or null > 0:
            raise Failure(
                "the matrix is not positive definite: MUMPS found %d negative and %d null pivots" % (negative, null)
            )
        self.factor_entries = f.getMumpsInfog(29)
        self.rows_per_rank = comm.allgather(self.layout.local)

    def solve(self, v):
        x = v.duplicate()
        self.ksp.solve(v, x)
        return x


class Driver:
    def __init__(self, job):
        self.job = job
        self.folder = os.path.dirname(os.path.abspath(job["path"]))
        self.factor = Factor(os.path.join(self.folder, job["stiffness"]), job.get("partitioner", "current"))

    def started(self):
        f = self.factor
        return {
            "ok": True,
            "ranks": size,
            "rows_per_rank": f.rows_per_rank,
            "factor_entries": f.factor_entries,
            "seconds": {"load": f.load_seconds, "partition": f.partition_seconds, "factor": f.factor_seconds},
            "peak_mib": comm.gather(peak_mib(), root=0),
        }

    def serve(self, channel):
        while True:
            header, payload = channel.receive()
            op = header.get("op")
            if op == "quit":
                channel.answer({"ok": True, "peak_mib": comm.gather(peak_mib(), root=0)})
                return
            try:
                serve = getattr(self, "op_" + str(op), None)
                if serve is None:
                    raise Failure("the driver has no request %r" % op)
                answer, doubles = serve(header, payload)
                answer["ok"] = True
            except Exception as e:  # noqa: BLE001 -- every failure goes back to the builder as its message
                traceback.print_exc()
                answer, doubles = {"ok": False, "error": reason(e)}, None
            channel.answer(answer, doubles)

    def op_stats(self, header, payload):
        return {"peak_mib": comm.gather(peak_mib(), root=0)}, None

    def op_solve(self, header, payload):
        """K^-1 B for a block of columns: MUMPS's multiple right-hand sides (MatMatSolve), one
        pass through the factor for the block instead of one per column."""
        layout = self.factor.layout
        n, count = layout.n, header["columns"]
        b = PETSc.Mat().createDense(((layout.local, n), (PETSc.DECIDE, count)), comm=PETSc.COMM_WORLD)
        b.setUp()
        b.getDenseArray()[:, :] = layout.spread_block(payload, count)
        b.assemble()
        x = b.duplicate()
        self.factor.ksp.getPC().getFactorMatrix().matSolve(b, x)
        out = layout.gather_block(x.getDenseArray())
        b.destroy()
        x.destroy()
        return {"columns": count}, out


def reason(e):
    """One line for the builder: the exception's first line, its type where it says nothing."""
    text = str(e).strip()
    return text.splitlines()[0] if text else type(e).__name__


def main():
    if sys.argv[1:] == ["--probe"]:
        # the builder's check before any work: this Python imports all the driver needs
        print(json.dumps({"petsc": PETSc.Sys.getVersion(), "python": sys.executable}))
        return 0
    job_path = sys.argv[1]
    with open(job_path) as f:
        job = json.load(f)
    job["path"] = job_path
    channel = Channel(job["host"], job["port"], job["token"])
    try:
        driver = Driver(job)
        started = driver.started()
    except Exception as e:  # noqa: BLE001 -- the builder reports it
        channel.answer({"ok": False, "error": reason(e)})
        # a rank that failed alone leaves the others in a collective call: end them all
        comm.Abort(1)
    channel.answer(started)
    driver.serve(channel)
    return 0


if __name__ == "__main__":
    # any failure ends every rank (MPI_Abort): no rank may wait in a collective call for one
    # that is gone, outliving the builder
    try:
        code = main()
    except Exception:  # noqa: BLE001 -- reported on stderr, then the job ends
        traceback.print_exc()
        sys.stderr.write("driver rank %d of %d failed: aborting the job\n" % (rank, size))
        sys.stderr.flush()
        comm.Abort(1)
    sys.exit(code)
