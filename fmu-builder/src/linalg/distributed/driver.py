"""The distributed back-end's driver: runs under MPI (mpirun -n N python3 driver.py JOB.json),
holds the mounted or shifted stiffness factored by MUMPS across the ranks, and serves the
builder's requests over one TCP connection from rank 0: solves, SLEPc eigen-solves, and
products with the mass matrices. The builder keeps the FE model and everything reduced; only
the sparse matrices (PETSc binary files in the job folder, read by rank 0 and distributed by
PETSc) and dense blocks of vectors cross to it.

Rows are distributed by PETSc's MatPartitioning (PT-Scotch where PETSc has it) of the
stiffness's graph, and every square matrix of the stiffness's size follows the same
distribution. Each request is a JSON line, then the little-endian doubles it announces; each
answer too. The builder writes this file into the job folder from its own copy, so driver and
builder always match.
"""

import json
import os
import resource
import socket
import struct
import sys
import time
import traceback


def debian_paths():
    """Debian's petsc4py and slepc4py find themselves through /usr/lib/petsc and /usr/lib/slepc,
    links only the -dev packages make: without them, PETSC_DIR and SLEPC_DIR name the install."""
    import glob

    for variable, link, pattern in [
        ("PETSC_DIR", "/usr/lib/petsc", "/usr/lib/petscdir/petsc*/*-linux-gnu-real"),
        ("SLEPC_DIR", "/usr/lib/slepc", "/usr/lib/slepcdir/slepc*/*-linux-gnu-real"),
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
import slepc4py  # noqa: E402

slepc4py.init(sys.argv[:1])
from mpi4py import MPI  # noqa: E402
from petsc4py import PETSc  # noqa: E402
from slepc4py import SLEPc  # noqa: E402

PROTOCOL = 1
comm = MPI.COMM_WORLD
rank = comm.Get_rank()
size = comm.Get_size()


class Failure(Exception):
    """A request that cannot be met: its message goes back to the builder."""


def peak_mib():
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


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
            data = bytes(doubles) if isinstance(doubles, (bytes, bytearray)) else struct.pack("<%dd" % len(doubles), *doubles)
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
    """Where each row of a matrix lives: `rows` the original rows this rank owns, in the order of
    its part of the distributed vectors; scatters move an n-vector held by rank 0 (in the
    builder's order) to and from that distribution."""

    def __init__(self, n, rows):
        self.n = n
        self.rows = rows
        self.local = rows.getLocalSize()
        self.whole = PETSc.Vec().createMPI((n if rank == 0 else 0, n), comm=PETSc.COMM_WORLD)
        self.template = PETSc.Vec().createMPI((self.local, n), comm=PETSc.COMM_WORLD)
        start, _ = self.template.getOwnershipRange()
        owned = PETSc.IS().createStride(self.local, first=start, step=1, comm=PETSc.COMM_WORLD)
        self.scatter = PETSc.Scatter().create(self.whole, rows, self.template, owned)

    def vector(self):
        return self.template.duplicate()

    def spread(self, column):
        """An n-vector from rank 0 (None elsewhere) to the distribution."""
        if rank == 0:
            self.whole.getArray()[:] = column
        v = self.vector()
        self.scatter.scatter(self.whole, v, addv=PETSc.InsertMode.INSERT, mode=PETSc.ScatterMode.FORWARD)
        return v

    def gather(self, v):
        """The distributed vector `v` on rank 0, in the builder's order (None elsewhere)."""
        self.scatter.scatter(v, self.whole, addv=PETSc.InsertMode.INSERT, mode=PETSc.ScatterMode.REVERSE)
        return self.whole.getArray().copy() if rank == 0 else None


def natural_layout(a):
    start, end = a.getOwnershipRange()
    rows = PETSc.IS().createStride(end - start, first=start, step=1, comm=PETSc.COMM_WORLD)
    return Layout(a.getSize()[0], rows)


def partitioned(a, partitioner):
    """`a` redistributed by PETSc's partitioning of its graph: the matrix in the new
    distribution and its layout."""
    n = a.getSize()[0]
    if size == 1:
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


def columns_of(payload, n, count):
    """Column j of an n x count column-major block (rank 0), None elsewhere."""
    for j in range(count):
        yield payload[j * n:(j + 1) * n] if rank == 0 else None


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


class WholeSolve:
    """PC applying K^-1 through the factor: SLEPc gets a KSP of its own (it resets the KSP it is
    given when done), the factor stays the session's."""

    def __init__(self, factor):
        self.factor = factor

    def apply(self, pc, b, x):
        self.factor.ksp.solve(b, x)


class HeldSolve:
    """PC of the held problem K_ii x = b (the trailing rows held) through the whole factor:
    z = K^-1 [b; 0], x = (z - G S^-1 z_b)_i with G = K^-1 E and S = E^T G, as the builder's
    in-process held solver does (no second factorisation)."""

    def __init__(self, factor, g, held_rows, keep):
        self.factor = factor
        self.g = g
        self.keep = keep
        h = len(g)
        # z_b gathered to every rank: h values
        held_is = PETSc.IS().createGeneral(held_rows if rank == 0 else [], comm=PETSc.COMM_SELF)
        self.held_values = PETSc.Vec().createSeq(h if rank == 0 else 0)
        # one scatter for every application: all vectors share the factor's layout
        self.held_scatter = PETSc.Scatter().create(factor.layout.template, held_is, self.held_values, None)
        s = [[0.0] * h for _ in range(h)]
        for j in range(h):
            values = self._held_of(g[j])
            for i in range(h):
                s[i][j] = values[i]
        s = [[0.5 * (s[i][j] + s[j][i]) for j in range(h)] for i in range(h)]
        self.s_inverse = invert(s)

    def _held_of(self, v):
        self.held_scatter.scatter(v, self.held_values, addv=PETSc.InsertMode.INSERT, mode=PETSc.ScatterMode.FORWARD)
        values = self.held_values.getArray().tolist() if rank == 0 else None
        return comm.bcast(values, root=0)

    def apply(self, pc, b, x):
        whole = self.factor.layout.vector()
        whole.set(0.0)
        sub = whole.getSubVector(self.keep)
        b.copy(sub)
        whole.restoreSubVector(self.keep, sub)
        z = self.factor.solve(whole)
        zb = self._held_of(z)
        h = len(self.g)
        z.maxpy([-sum(self.s_inverse[j][i] * zb[i] for i in range(h)) for j in range(h)], self.g)
        sub = z.getSubVector(self.keep)
        sub.copy(x)
        z.restoreSubVector(self.keep, sub)


def invert(s):
    """Inverse of a small SPD matrix by Gauss-Jordan (the held DoFs' compliance, 6 per flange)."""
    n = len(s)
    a = [row[:] + [1.0 if i == j else 0.0 for j in range(n)] for i, row in enumerate(s)]
    for c in range(n):
        p = max(range(c, n), key=lambda r: abs(a[r][c]))
        a[c], a[p] = a[p], a[c]
        if a[c][c] == 0.0:
            raise Failure("the held DoFs' compliance is singular")
        inv = 1.0 / a[c][c]
        a[c] = [v * inv for v in a[c]]
        for r in range(n):
            if r != c and a[r][c] != 0.0:
                f = a[r][c]
                a[r] = [vr - f * vc for vr, vc in zip(a[r], a[c])]
    return [row[n:] for row in a]


class Driver:
    def __init__(self, job):
        self.job = job
        self.folder = os.path.dirname(os.path.abspath(job["path"]))
        self.factor = Factor(os.path.join(self.folder, job["stiffness"]), job.get("partitioner", "ptscotch"))
        # matrices loaded on request: id -> (matrix, layout)
        self.matrices = {}

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
                answer, doubles = getattr(self, "op_" + op)(header, payload)
                answer["ok"] = True
            except Exception as e:  # noqa: BLE001 -- every failure goes back to the builder as its message
                traceback.print_exc()
                answer, doubles = {"ok": False, "error": reason(e)}, None
            channel.answer(answer, doubles)

    def op_stats(self, header, payload):
        return {"peak_mib": comm.gather(peak_mib(), root=0)}, None

    def op_load(self, header, payload):
        a = load(os.path.join(self.folder, header["file"]))
        n = a.getSize()[0]
        if n == self.factor.layout.n:
            b = a.createSubMatrix(self.factor.layout.rows, self.factor.layout.rows) if size > 1 else a
            layout = self.factor.layout
        else:
            b, layout = a, natural_layout(a)
        self.matrices[header["id"]] = (b, layout)
        return {}, None

    def op_solve(self, header, payload):
        """K^-1 B for a block of columns: MUMPS's multiple right-hand sides (MatMatSolve), one
        pass through the factor for the block instead of one per column."""
        layout = self.factor.layout
        n, count = layout.n, header["columns"]
        b = PETSc.Mat().createDense(((layout.local, n), (PETSc.DECIDE, count)), comm=PETSc.COMM_WORLD)
        b.setUp()
        block = b.getDenseArray()
        for j, column in enumerate(columns_of(payload, n, count)):
            block[:, j] = layout.spread(column).getArray()
        b.assemble()
        x = b.duplicate()
        self.factor.ksp.getPC().getFactorMatrix().matSolve(b, x)
        out = bytearray() if rank == 0 else None
        for j in range(count):
            result = layout.gather(x.getColumnVector(j))
            if rank == 0:
                out += result.tobytes()
        b.destroy()
        x.destroy()
        return {"columns": count}, out

    def op_inner(self, header, payload):
        """A^T M B for the matrix `id` (A: a columns, B: b columns, column-major)."""
        m, layout = self.matrices[header["id"]]
        n, a_count, b_count = layout.n, header["a"], header["b"]
        a_columns = [layout.spread(c) for c in columns_of(payload, n, a_count)]
        rest = payload[n * a_count:] if rank == 0 else None
        result = [[0.0] * b_count for _ in range(a_count)]
        y = layout.vector()
        for j, column in enumerate(columns_of(rest, n, b_count)):
            m.mult(layout.spread(column), y)
            for i in range(a_count):
                result[i][j] = a_columns[i].dot(y)
        flat = [result[i][j] for j in range(b_count) for i in range(a_count)]
        return {"rows": a_count, "columns": b_count}, flat

    def op_eigen(self, header, payload):
        """Lowest eigenpairs of K x = lambda M x by SLEPc's Krylov-Schur in shift-invert about 0
        (K is the factored matrix, possibly K + shift M), optionally with trailing rows held and
        vectors deflated; `count` pairs, or all below `below` (lambda), at least `min_count`."""
        f = self.factor
        m, layout = self.matrices[header["mass"]]
        n = layout.n
        deflate_count = header.get("deflate", 0)
        held_count = header.get("held", 0)
        deflate = [layout.spread(c) for c in columns_of(payload, n, deflate_count)]
        rest = payload[n * deflate_count:] if rank == 0 else None
        g = [layout.spread(c) for c in columns_of(rest, n, held_count)]
        a, b = f.k, m
        ksp = PETSc.KSP().create(comm=PETSc.COMM_WORLD)
        ksp.setType("preonly")
        pc = ksp.getPC()
        pc.setType("python")
        pc.setPythonContext(WholeSolve(f))
        keep = None
        if held_count:
            first = n - held_count
            # this rank's rows (new numbering) whose original row is kept free
            start, _ = layout.template.getOwnershipRange()
            original = layout.rows.getIndices()
            kept = [start + i for i, r in enumerate(original) if r < first]
            held_new = comm.gather([start + i for i, r in enumerate(original) if r >= first], root=0)
            held_original = comm.gather([int(r) for r in original if r >= first], root=0)
            if rank == 0:
                pairs = sorted(zip(sum(held_original, []), sum(held_new, [])))
                held_rows = [new for _, new in pairs]
            else:
                held_rows = []
            keep = PETSc.IS().createGeneral(kept, comm=PETSc.COMM_WORLD)
            a = f.k.createSubMatrix(keep, keep)
            b = m.createSubMatrix(keep, keep)
            pc.setPythonContext(HeldSolve(f, g, held_rows, keep))
        eps = SLEPc.EPS().create(comm=PETSc.COMM_WORLD)
        eps.setOperators(a, b)
        eps.setProblemType(SLEPc.EPS.ProblemType.GHEP)
        eps.setWhichEigenpairs(SLEPc.EPS.Which.TARGET_MAGNITUDE)
        eps.setTarget(0.0)
        st = eps.getST()
        st.setType("sinvert")
        st.setShift(0.0)
        st.setKSP(ksp)
        eps.setTolerances(header.get("tol", 1e-12), 10000)
        if deflate:
            eps.setDeflationSpace(deflate)
        below = header.get("below")
        # guard pairs beyond those wanted: the builder's Rayleigh-Ritz step resolves the wanted
        # ones against them
        guard = header.get("guard", 0)
        limit = n - held_count - deflate_count
        wanted = min(max(header.get("count", 0), header.get("min_count", 0), 1 if below is None else 10), limit)
        while True:
            nev = min(wanted + guard, limit)
            eps.setDimensions(nev=nev, ncv=min(max(2 * nev, nev + 16), limit))
            eps.solve()
            found = eps.getConverged()
            if found < nev:
                raise Failure("SLEPc found %d of %d eigenpairs" % (found, nev))
            values = sorted(eps.getEigenvalue(i).real for i in range(found))
            if below is None or nev >= limit or values[max(nev - guard - 1, 0)] > below:
                break
            wanted = min(2 * wanted, limit)
        order = sorted(range(found), key=lambda i: eps.getEigenvalue(i).real)
        if below is not None:
            inside = sum(1 for i in order if eps.getEigenvalue(i).real <= below)
            wanted = max(inside, header.get("min_count", 0))
        order = order[: min(wanted + guard, found)]
        x = a.createVecRight()
        values = []
        out = bytearray() if rank == 0 else None
        whole = layout.vector()
        for i in order:
            values.append(eps.getEigenpair(i, x).real)
            if keep is not None:
                whole.set(0.0)
                sub = whole.getSubVector(keep)
                x.copy(sub)
                whole.restoreSubVector(keep, sub)
                v = layout.gather(whole)
            else:
                v = layout.gather(x)
            if rank == 0:
                out += v.tobytes()
        iterations = eps.getIterationNumber()
        eps.destroy()
        return {"values": values, "iterations": iterations, "rows": n}, out


def reason(e):
    """One line for the builder: the exception's first line, its type where it says nothing."""
    text = str(e).strip()
    return text.splitlines()[0] if text else type(e).__name__


def main():
    if sys.argv[1:] == ["--probe"]:
        # the builder's check before any work: this Python imports all the driver needs
        print(json.dumps({"petsc": PETSc.Sys.getVersion(), "slepc": SLEPc.Sys.getVersion(), "python": sys.executable}))
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
