#!/usr/bin/env python3
"""FMI 2.0 call-sequence fuzzer: random calls from the whole fmi2 API, through ctypes, on built FMUs.

Each batch of sequences runs in a forked child process (the parent never loads an FMU binary),
so a crash (a signal) or a hang (the batch's time limit) is counted; a failing batch is rerun
sequence by sequence to find the culprit. Calls: instantiate (ME and CS, right and wrong GUID),
setup, enter/exit initialisation, get/set of Real/Integer/Boolean/String with valid and invalid
value references, set time and continuous states, derivatives, event indicators, nominals,
event and continuous-time mode, do step with random step sizes, get/set/free FMU state,
serialize/deserialize (bit flips, truncation, bytes of another FMU or instance), directional and
output derivatives, input derivatives, debug logging, reset, terminate, free. Values include NaN,
+-inf, +-1e308, 0, -0, denormals. Classes aimed at the range checks: huge steps (1e200, 1e306,
1e308) and long ones (16 s, 100 s) of a free body spun to 300 rad/s, input derivatives and
directional seeds of 1e200..1e308, mount rotations set whole or entry by entry (rotations,
interpolated ones, non-orthogonal and mirrored matrices), free-body states whose quaternion is
no orientation (norm 0 or 1e200).

Oracle, after every call: no crash, no hang, no panic reported by the model, every status other
than fmi2OK comes with a message logged during the call (logging is on), and nothing non-finite
is returned with fmi2OK or fmi2Warning (every output array is checked). A step answered with
fmi2OK or fmi2Warning leaves a state that reads (fmi2GetReal of every modal and frame state:
fmi2OK, finite); a step answered with fmi2Discard leaves the slave in stepFailed with
fmi2LastSuccessfulTime at the step's start and its state readable; a refusal (fmi2Error) of
fmi2SetReal, fmi2SetRealInputDerivatives, fmi2GetDirectionalDerivative or fmi2DoStep does not
put the instance into the Error state (the state is probed with fmi2CancelStep, which is refused
in every state and names it). Each distinct violation
is printed once with a minimal reproducer (calls removed while the violation stays).

    python tests/fuzz/fmi_sequences.py --seconds 60 --seed 1 [--fmu A.fmu B.fmu ...]

Without --fmu it builds three FMUs from examples/ with target/release/fmu-builder: the mounted
beam, the spinning T-square (rotation declared) and a free-floating beam. Exit status 1 on any
crash, hang or violation.
"""

import argparse
import ctypes
import json
import math
import multiprocessing
import os
import random
import shutil
import signal
import struct
import subprocess
import sys
import tempfile
import time
import zipfile
import xml.etree.ElementTree as ET
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
# CARGO_TARGET_DIR as cargo reads it: a build elsewhere is tested where it was built
BUILDER = Path(os.environ.get("CARGO_TARGET_DIR", ROOT / "target")) / "release" / "fmu-builder"

VALUES = [float("nan"), float("inf"), float("-inf"), 1e308, -1e308, 0.0, -0.0, 5e-324, 2.2250738585072014e-308,
          -1.0, 1.0, 0.5, 3.0, 10.0, 1e3, 1e6, -1e6, 1e-9]
STEPS = [0.0, -1.0, 1e-12, 1e-6, 1e-3, 0.01, 0.1, 1.0, 16.0, 100.0, 1e200, 1e306, 1e308, float("nan"), float("inf"),
         5e-324]
# rates (input derivatives, directional seeds) beyond the range of any physical quantity
HUGE = [1e200, -1e250, 1e300, 1e306, 1e308, -1e308]
INTS = [0, 1, -1, 2, 2**31 - 1, -2**31]
BAD_VRS = [999999, 2**32 - 1, 2**31, 12345678]


# --------------------------------------------------------------------------------------------
# FMUs

def build_fmus(directory):
    """The mounted beam, the spinning T-square and a free-floating beam, built from examples/."""
    directory = Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    specs = {"beam": json.loads((ROOT / "examples/beam.json").read_text()),
             "tsquare": json.loads((ROOT / "examples/t-square.json").read_text())}
    free = json.loads((ROOT / "examples/beam.json").read_text())
    free["name"] = "FreeBeam"
    free["flanges"][0]["role"] = "force"
    free["reduction"] = {"method": "craig_bampton", "modes": 6}
    free["scene"] = {"loads": ["gravity", "rotation"]}
    specs["free"] = free
    out = []
    for name, spec in specs.items():
        spec.pop("$schema", None)
        spec_path = directory / f"{name}.json"
        spec_path.write_text(json.dumps(spec))
        fmu = directory / f"{name}.fmu"
        if not fmu.exists():
            proc = subprocess.run([str(BUILDER), str(spec_path), "-o", str(fmu)], capture_output=True, text=True,
                                  timeout=900)
            if proc.returncode != 0:
                raise SystemExit(f"building {name} failed:\n{proc.stdout}\n{proc.stderr}")
        out.append(str(fmu))
    return out


def describe(fmu_path, extract_root):
    """What the sequences need of an FMU: binary, GUID, variables by type and causality."""
    directory = Path(extract_root) / Path(fmu_path).stem
    if directory.exists():
        shutil.rmtree(directory)
    zipfile.ZipFile(fmu_path).extractall(directory)
    root = ET.parse(directory / "modelDescription.xml").getroot()
    ident = root.find("CoSimulation").get("modelIdentifier")
    info = {"path": str(fmu_path), "dir": str(directory), "guid": root.get("guid"),
            "binary": str(directory / "binaries" / "linux64" / f"{ident}.so"),
            "resources": (directory / "resources").as_uri(),
            "nz": int(root.get("numberOfEventIndicators", "0")), "vars": {}}
    for v in root.find("ModelVariables"):
        kind = next(iter(v)).tag
        info["vars"].setdefault(kind, []).append((int(v.get("valueReference")), v.get("causality", "local"),
                                                  v.get("variability", "continuous"), v.get("name")))
    derivatives = root.find("ModelStructure/Derivatives")
    info["nx"] = 0 if derivatives is None else len(list(derivatives))
    return info


# --------------------------------------------------------------------------------------------
# sequences: lists of JSON-able calls

def random_call(rng, fmus):
    r = rng.random
    slot = rng.randrange(2)
    op = rng.choice(OPS)
    if op == "instantiate":
        return [op, slot, rng.randrange(len(fmus)), rng.choice([0, 1]), r() < 0.95]
    if op == "setup":
        return [op, slot, rng.choice([0, 1]), rng.choice(VALUES), rng.choice([0.0, 0.0, 1.0, -1.0, rng.choice(VALUES)]),
                rng.choice([0, 1]), rng.choice(VALUES)]
    if op in ("set_real", "get_real", "set_integer", "get_integer", "set_boolean", "get_boolean",
              "set_string", "get_string", "set_input_derivatives", "get_output_derivatives"):
        n = rng.choice([0, 1, 1, 2, 3, 8])
        vrs = [("bad", rng.choice(BAD_VRS)) if r() < 0.1 else ("idx", rng.randrange(10**6)) for _ in range(n)]
        pool = VALUES + HUGE if op == "set_input_derivatives" else VALUES
        values = [rng.choice(pool) if r() < 0.7 else rng.uniform(-10, 10) for _ in range(n)]
        ints = [rng.choice(INTS) for _ in range(n)]
        return [op, slot, vrs, values, ints]
    if op == "set_rotation":
        return [op, slot, rng.choice(["rotation", "interpolated", "sheared", "random", "mirrored", "huge"]),
                rng.uniform(-3.2, 3.2), rng.choice([9, 9, 9, 1, 3]), rng.randrange(9)]
    if op == "bad_quaternion":
        return [op, slot, rng.choice([[0.0, 0.0, 0.0, 0.0], [1e200, 0.0, 0.0, 0.0], [1e200, 1e200, -1e200, 1e200],
                                      [1e-200, 0.0, 0.0, 0.0], [1.0, 0.0, 0.0, 0.0]])]
    if op == "spin":
        return [op, slot, rng.choice([30.0, 300.0, 3000.0, 1e6])]
    if op == "set_time":
        return [op, slot, rng.choice(VALUES + [0.0, 0.1, 1.0])]
    if op in ("set_states", "get_states", "get_derivatives", "get_event_indicators", "get_nominals"):
        return [op, slot, rng.choice([0, 0, 0, 0, 1, -1, 5]), [rng.choice(VALUES) if r() < 0.5 else rng.uniform(-1, 1)
                                                               for _ in range(16)]]
    if op == "do_step":
        return [op, slot, "cur" if r() < 0.85 else rng.choice(VALUES), rng.choice(STEPS), rng.choice([0, 1])]
    if op in ("get_state", "set_state", "free_state"):
        return [op, slot, rng.randrange(3)]
    if op == "serialize":
        return [op, slot, rng.randrange(3), rng.randrange(3), r() < 0.1]
    if op == "deserialize":
        return [op, slot, rng.randrange(3), rng.randrange(3),
                rng.choice(["none", "none", "flip", "truncate", "extend", "zero"]), rng.randrange(10**6), rng.randrange(1, 256)]
    if op == "directional":
        n, m = rng.choice([1, 2, 3]), rng.choice([1, 2, 3])
        return [op, slot, [rng.randrange(10**6) for _ in range(n)], [rng.randrange(10**6) for _ in range(m)],
                [rng.choice(VALUES + HUGE) if r() < 0.5 else rng.uniform(-1, 1) for _ in range(m)], r() < 0.1]
    if op == "debug_logging":
        return [op, slot, rng.choice([0, 1])]
    if op == "real_status":
        return [op, slot, rng.randrange(5)]
    return [op, slot]


OPS = (["instantiate"] * 3 + ["setup", "enter_init", "exit_init"] * 3 + ["terminate", "reset", "free"]
       + ["set_real"] * 6 + ["get_real"] * 4 + ["set_integer", "get_integer", "set_boolean", "get_boolean",
                                                 "set_string", "get_string"]
       + ["set_time", "set_states", "get_states", "get_derivatives", "get_derivatives", "get_event_indicators",
          "get_nominals", "enter_event_mode", "new_discrete_states", "enter_continuous_time_mode",
          "completed_integrator_step"]
       + ["do_step"] * 6 + ["get_state", "set_state", "free_state", "serialize", "deserialize", "deserialize"]
       + ["directional", "directional", "set_input_derivatives", "get_output_derivatives", "debug_logging",
          "real_status", "cancel_step"]
       + ["set_rotation", "set_rotation", "bad_quaternion", "spin"])


def random_sequence(rng, fmus, length):
    # most sequences start usefully: an instance set up and initialised
    seq = []
    if rng.random() < 0.8:
        slot_fmu = rng.randrange(len(fmus))
        seq += [["instantiate", 0, slot_fmu, rng.choice([0, 1]), True], ["setup", 0, 0, 0.0, 0.0, 0, 0.0],
                ["enter_init", 0], ["exit_init", 0]]
    seq += [random_call(rng, fmus) for _ in range(length)]
    return seq


# --------------------------------------------------------------------------------------------
# the child: runs sequences against the FMU binaries

OK, WARNING, DISCARD, ERROR, FATAL, PENDING = range(6)
LOGGER = ctypes.CFUNCTYPE(None, ctypes.c_void_p, ctypes.c_char_p, ctypes.c_int, ctypes.c_char_p, ctypes.c_char_p,
                          ctypes.c_char_p)


class Callbacks(ctypes.Structure):
    _fields_ = [("logger", LOGGER), ("allocateMemory", ctypes.c_void_p), ("freeMemory", ctypes.c_void_p),
                ("stepFinished", ctypes.c_void_p), ("componentEnvironment", ctypes.c_void_p)]


class EventInfo(ctypes.Structure):
    _fields_ = [("newDiscreteStatesNeeded", ctypes.c_int), ("terminateSimulation", ctypes.c_int),
                ("nominalsOfContinuousStatesChanged", ctypes.c_int), ("valuesOfContinuousStatesChanged", ctypes.c_int),
                ("nextEventTimeDefined", ctypes.c_int), ("nextEventTime", ctypes.c_double)]


class Runner:
    """Executes calls; collects (key, text) violations."""

    def __init__(self, fmus):
        self.fmus = fmus
        self.libs = [ctypes.CDLL(f["binary"]) for f in fmus]
        self.log = []
        self.logger = LOGGER(self._log)
        self.callbacks = Callbacks(self.logger, None, None, None, None)

    def _log(self, env, name, status, category, fmt, arg):
        text = arg if fmt == b"%s" and arg is not None else fmt
        self.log.append((status, (text or b"").decode(errors="replace")))

    def run(self, seq):
        self.slots = [None, None]  # (lib, component, fmu index, kind, time)
        self.states = [[None] * 3, [None] * 3]
        self.serialized = [None] * 3
        self.violations = []
        for k, call in enumerate(seq):
            self.call_index = k
            try:
                getattr(self, "op_" + call[0])(*call[1:])
            except _Skip:
                pass
        for slot in range(2):
            if self.slots[slot]:
                self.op_free(slot)
        return self.violations

    # ---- checking

    def check(self, function, status, mark):
        logged = self.log[mark:]
        for s, text in logged:
            if "panic" in text:
                self.violate(f"panic:{function}", f"{function}: {text}")
        if status not in (OK, WARNING, DISCARD, ERROR, FATAL, PENDING):
            self.violate(f"status:{function}", f"{function} returned status {status}")
        elif (status >= ERROR or (status != OK and self.slots[self.current][5])) and not any(s != OK for s, _ in logged):
            self.violate(f"nomessage:{function}:{status}", f"{function} returned status {status} without a logged message")
        return status in (OK, WARNING)

    def finite(self, function, values):
        bad = [v for v in values if not math.isfinite(v)]
        if bad:
            self.violate(f"nonfinite:{function}", f"{function} returned {bad[0]} with fmi2OK/fmi2Warning")

    def probe_state(self, slot):
        """The instance's FMI state as fmi2CancelStep names it (refused in every state we enter);
        None for Model Exchange or when it cannot tell."""
        c, info, kind = self.need(slot)
        if kind != 1:
            return None
        mark = len(self.log)
        self.slot_lib.fmi2CancelStep.restype = ctypes.c_int
        self.slot_lib.fmi2CancelStep(c)
        for _, text in self.log[mark:]:
            if "called in state " in text:
                return text.split("called in state ")[1].split(";")[0]
        return None

    def still_usable(self, slot, function, status, before):
        """A refusal (fmi2Error) of a range or input check keeps the instance out of Error."""
        if status == ERROR and before not in (None, "Error") and self.probe_state(slot) == "Error":
            self.violate(f"unusable:{function}", f"{function} refused with fmi2Error and left the instance in Error "
                         f"(it was in {before})")

    def state_vars(self, info):
        return [vr for vr, causality, variability, name in info["vars"].get("Real", [])
                if name.startswith(("q[", "qd[", "frame."))]

    def read_state(self, slot, function, required):
        """Every modal and frame state through fmi2GetReal: fmi2OK and finite where `required`."""
        c, info, kind = self.need(slot)
        vrs = self.state_vars(info)
        if not vrs:
            return
        vr = (ctypes.c_uint * len(vrs))(*vrs)
        out = (ctypes.c_double * len(vrs))()
        status, mark = self.call("fmi2GetReal", c, vr, ctypes.c_size_t(len(vrs)), out)
        self.check("fmi2GetReal", status, mark)
        if required and status != OK:
            self.violate(f"unreadable-after:{function}", f"{function}: the state then reads with status {status}: "
                         + "; ".join(t for _, t in self.log[mark:]))
        if status in (OK, WARNING):
            bad = [v for v in out[:len(vrs)] if not math.isfinite(v)]
            if bad:
                self.violate(f"nonfinite-state-after:{function}", f"{function} left the state value {bad[0]}")

    def violate(self, key, text):
        self.violations.append((key, text, self.call_index))

    def call(self, function, *args, restype=ctypes.c_int):
        lib = self.slot_lib
        f = getattr(lib, function)
        f.restype = restype
        mark = len(self.log)
        status = f(*args)
        return status, mark

    def need(self, slot):
        if self.slots[slot] is None:
            raise _Skip()
        lib, c, fi, kind, t, logging = self.slots[slot]
        self.slot_lib = lib
        self.current = slot
        return c, self.fmus[fi], kind

    def vrs(self, info, picks, kind="Real"):
        pool = info["vars"].get(kind) or info["vars"]["Real"]
        return [v if tag == "bad" else pool[v % len(pool)][0] for tag, v in picks]

    # ---- calls

    def op_instantiate(self, slot, fi, kind, right_guid):
        if self.slots[slot] is not None:
            self.op_free(slot)
        info = self.fmus[fi]
        lib = self.libs[fi]
        lib.fmi2Instantiate.restype = ctypes.c_void_p
        lib.fmi2Instantiate.argtypes = [ctypes.c_char_p, ctypes.c_int, ctypes.c_char_p, ctypes.c_char_p,
                                        ctypes.c_void_p, ctypes.c_int, ctypes.c_int]
        guid = info["guid"] if right_guid else "{00000000-0000-0000-0000-000000000000}"
        mark = len(self.log)
        c = lib.fmi2Instantiate(b"fuzz", kind, guid.encode(), info["resources"].encode(),
                                ctypes.addressof(self.callbacks), 0, 1)
        if not c:
            if not any(s != OK for s, _ in self.log[mark:]):
                self.violate("nomessage:fmi2Instantiate", "fmi2Instantiate returned NULL without a logged message")
            return
        # logging on: Warning and Discard need a message too (errors always do)
        self.slots[slot] = [lib, ctypes.c_void_p(c), fi, kind, 0.0, True]

    def op_free(self, slot):
        c, info, kind = self.need(slot)
        for k in range(3):
            if self.states[slot][k] is not None:
                self.op_free_state(slot, k)
        self.slot_lib.fmi2FreeInstance.restype = None
        self.slot_lib.fmi2FreeInstance(c)
        self.slots[slot] = None

    def simple(self, slot, function):
        c, info, kind = self.need(slot)
        status, mark = self.call(function, c)
        return self.check(function, status, mark)

    def op_setup(self, slot, tol_defined, tol, start, stop_defined, stop):
        c, info, kind = self.need(slot)
        status, mark = self.call("fmi2SetupExperiment", c, ctypes.c_int(tol_defined), ctypes.c_double(tol),
                                 ctypes.c_double(start), ctypes.c_int(stop_defined), ctypes.c_double(stop))
        if self.check("fmi2SetupExperiment", status, mark) and math.isfinite(start):
            self.slots[slot][4] = start

    def op_enter_init(self, slot):
        self.simple(slot, "fmi2EnterInitializationMode")

    def op_exit_init(self, slot):
        self.simple(slot, "fmi2ExitInitializationMode")

    def op_terminate(self, slot):
        self.simple(slot, "fmi2Terminate")

    def op_reset(self, slot):
        if self.simple(slot, "fmi2Reset"):
            self.slots[slot][4] = 0.0

    def op_enter_event_mode(self, slot):
        self.simple(slot, "fmi2EnterEventMode")

    def op_enter_continuous_time_mode(self, slot):
        self.simple(slot, "fmi2EnterContinuousTimeMode")

    def op_cancel_step(self, slot):
        self.simple(slot, "fmi2CancelStep")

    def op_new_discrete_states(self, slot):
        c, info, kind = self.need(slot)
        ev = EventInfo()
        status, mark = self.call("fmi2NewDiscreteStates", c, ctypes.byref(ev))
        if self.check("fmi2NewDiscreteStates", status, mark) and ev.nextEventTimeDefined:
            self.finite("fmi2NewDiscreteStates", [ev.nextEventTime])

    def op_completed_integrator_step(self, slot):
        c, info, kind = self.need(slot)
        a, b = ctypes.c_int(0), ctypes.c_int(0)
        status, mark = self.call("fmi2CompletedIntegratorStep", c, ctypes.c_int(1), ctypes.byref(a), ctypes.byref(b))
        self.check("fmi2CompletedIntegratorStep", status, mark)

    def op_debug_logging(self, slot, on):
        c, info, kind = self.need(slot)
        status, mark = self.call("fmi2SetDebugLogging", c, ctypes.c_int(on), ctypes.c_size_t(0), None)
        if self.check("fmi2SetDebugLogging", status, mark):
            self.slots[slot][5] = bool(on)

    def op_real_status(self, slot, which):
        c, info, kind = self.need(slot)
        v = ctypes.c_double(0.0)
        status, mark = self.call("fmi2GetRealStatus", c, ctypes.c_int(which), ctypes.byref(v))
        if self.check("fmi2GetRealStatus", status, mark):
            self.finite("fmi2GetRealStatus", [v.value])

    def op_set_real(self, slot, picks, values, ints):
        c, info, kind = self.need(slot)
        vr = (ctypes.c_uint * max(1, len(picks)))(*self.vrs(info, picks))
        val = (ctypes.c_double * max(1, len(values)))(*values)
        before = self.probe_state(slot)
        status, mark = self.call("fmi2SetReal", c, vr, ctypes.c_size_t(len(picks)), val)
        self.check("fmi2SetReal", status, mark)
        self.still_usable(slot, "fmi2SetReal", status, before)

    def op_set_rotation(self, slot, kind_of, angle, count, first):
        """The mount's orientation base.R: all nine entries in one call, or some of them."""
        c, info, kind = self.need(slot)
        names = {name: vr for vr, _, _, name in info["vars"].get("Real", [])}
        entries = [f"base.R[{i},{j}]" for i in (1, 2, 3) for j in (1, 2, 3)]
        if entries[0] not in names:
            raise _Skip()
        ca, sa = math.cos(angle), math.sin(angle)
        rot = [ca, -sa, 0.0, sa, ca, 0.0, 0.0, 0.0, 1.0]
        if kind_of == "interpolated":
            cb, sb = math.cos(angle + 0.1), math.sin(angle + 0.1)
            rot = [0.5 * (x + y) for x, y in zip(rot, [cb, -sb, 0.0, sb, cb, 0.0, 0.0, 0.0, 1.0])]
        elif kind_of == "sheared":
            rot[1] += 0.8
        elif kind_of == "random":
            rng = random.Random(angle)
            rot = [rng.uniform(-1, 1) for _ in range(9)]
        elif kind_of == "mirrored":
            rot[8] = -1.0
        elif kind_of == "huge":
            rot = [1e200 * x for x in rot]
        picked = [(first + k) % 9 for k in range(count)]
        vr = (ctypes.c_uint * count)(*[names[entries[k]] for k in picked])
        val = (ctypes.c_double * count)(*[rot[k] for k in picked])
        before = self.probe_state(slot)
        status, mark = self.call("fmi2SetReal", c, vr, ctypes.c_size_t(count), val)
        self.check("fmi2SetReal", status, mark)
        self.still_usable(slot, "fmi2SetReal", status, before)

    def op_bad_quaternion(self, slot, quat):
        """A free body's states (Model Exchange) with its quaternion replaced."""
        c, info, kind = self.need(slot)
        names = [name for _, _, _, name in info["vars"].get("Real", [])]
        if kind != 0 or "frame.Q[1]" not in names or info["nx"] < 13:
            raise _Skip()
        n = info["nx"]
        x = (ctypes.c_double * n)()
        status, mark = self.call("fmi2GetContinuousStates", c, x, ctypes.c_size_t(n))
        if not self.check("fmi2GetContinuousStates", status, mark):
            return
        # the frame's states come last: r[3], Q[4], v[3], W[3]
        for k in range(4):
            x[n - 10 + k] = quat[k]
        status, mark = self.call("fmi2SetContinuousStates", c, x, ctypes.c_size_t(n))
        self.check("fmi2SetContinuousStates", status, mark)

    def op_spin(self, slot, w):
        """A free body's initial spin (a parameter: accepted before initialisation ends)."""
        c, info, kind = self.need(slot)
        names = {name: vr for vr, _, _, name in info["vars"].get("Real", [])}
        if "initial.w[3]" not in names:
            raise _Skip()
        vr = (ctypes.c_uint * 1)(names["initial.w[3]"])
        val = (ctypes.c_double * 1)(w)
        status, mark = self.call("fmi2SetReal", c, vr, ctypes.c_size_t(1), val)
        self.check("fmi2SetReal", status, mark)

    def op_get_real(self, slot, picks, values, ints):
        c, info, kind = self.need(slot)
        n = len(picks)
        vr = (ctypes.c_uint * max(1, n))(*self.vrs(info, picks))
        out = (ctypes.c_double * max(1, n))()
        status, mark = self.call("fmi2GetReal", c, vr, ctypes.c_size_t(n), out)
        if self.check("fmi2GetReal", status, mark):
            self.finite("fmi2GetReal", out[:n])

    def op_set_integer(self, slot, picks, values, ints):
        self._set_int(slot, picks, ints, "fmi2SetInteger", "Integer")

    def op_set_boolean(self, slot, picks, values, ints):
        self._set_int(slot, picks, ints, "fmi2SetBoolean", "Boolean")

    def _set_int(self, slot, picks, ints, function, kind_name):
        c, info, kind = self.need(slot)
        vr = (ctypes.c_uint * max(1, len(picks)))(*self.vrs(info, picks, kind_name))
        val = (ctypes.c_int * max(1, len(ints)))(*ints)
        status, mark = self.call(function, c, vr, ctypes.c_size_t(len(picks)), val)
        self.check(function, status, mark)

    def op_get_integer(self, slot, picks, values, ints):
        self._get_int(slot, picks, "fmi2GetInteger", "Integer")

    def op_get_boolean(self, slot, picks, values, ints):
        self._get_int(slot, picks, "fmi2GetBoolean", "Boolean")

    def _get_int(self, slot, picks, function, kind_name):
        c, info, kind = self.need(slot)
        n = len(picks)
        vr = (ctypes.c_uint * max(1, n))(*self.vrs(info, picks, kind_name))
        out = (ctypes.c_int * max(1, n))()
        status, mark = self.call(function, c, vr, ctypes.c_size_t(n), out)
        self.check(function, status, mark)

    def op_set_string(self, slot, picks, values, ints):
        c, info, kind = self.need(slot)
        n = len(picks)
        vr = (ctypes.c_uint * max(1, n))(*self.vrs(info, picks, "String"))
        val = (ctypes.c_char_p * max(1, n))(*[repr(v).encode() for v in values])
        status, mark = self.call("fmi2SetString", c, vr, ctypes.c_size_t(n), val)
        self.check("fmi2SetString", status, mark)

    def op_get_string(self, slot, picks, values, ints):
        c, info, kind = self.need(slot)
        n = len(picks)
        vr = (ctypes.c_uint * max(1, n))(*self.vrs(info, picks, "String"))
        out = (ctypes.c_char_p * max(1, n))()
        status, mark = self.call("fmi2GetString", c, vr, ctypes.c_size_t(n), out)
        if self.check("fmi2GetString", status, mark) and any(out[k] is None for k in range(n)):
            self.violate("nullstring:fmi2GetString", "fmi2GetString returned a NULL string with fmi2OK")

    def op_set_input_derivatives(self, slot, picks, values, ints):
        c, info, kind = self.need(slot)
        n = len(picks)
        vr = (ctypes.c_uint * max(1, n))(*self.vrs(info, picks))
        order = (ctypes.c_int * max(1, n))(*[1 if i % 3 else abs(i) % 3 for i in ints])
        val = (ctypes.c_double * max(1, n))(*values)
        before = self.probe_state(slot)
        status, mark = self.call("fmi2SetRealInputDerivatives", c, vr, ctypes.c_size_t(n), order, val)
        self.check("fmi2SetRealInputDerivatives", status, mark)
        self.still_usable(slot, "fmi2SetRealInputDerivatives", status, before)

    def op_get_output_derivatives(self, slot, picks, values, ints):
        c, info, kind = self.need(slot)
        n = len(picks)
        vr = (ctypes.c_uint * max(1, n))(*self.vrs(info, picks))
        order = (ctypes.c_int * max(1, n))(*[1 if i % 3 else abs(i) % 3 for i in ints])
        out = (ctypes.c_double * max(1, n))()
        status, mark = self.call("fmi2GetRealOutputDerivatives", c, vr, ctypes.c_size_t(n), order, out)
        if self.check("fmi2GetRealOutputDerivatives", status, mark):
            self.finite("fmi2GetRealOutputDerivatives", out[:n])

    def op_set_time(self, slot, t):
        c, info, kind = self.need(slot)
        status, mark = self.call("fmi2SetTime", c, ctypes.c_double(t))
        self.check("fmi2SetTime", status, mark)

    def _n(self, info, delta, which="nx"):
        return max(0, info[which] + delta) if delta != 5 else info[which] + 5

    def op_set_states(self, slot, delta, values):
        c, info, kind = self.need(slot)
        n = self._n(info, delta)
        vals = (values * (n // len(values) + 1))[:n]
        arr = (ctypes.c_double * max(1, n))(*vals)
        status, mark = self.call("fmi2SetContinuousStates", c, arr, ctypes.c_size_t(n))
        self.check("fmi2SetContinuousStates", status, mark)

    def _get_array(self, slot, delta, function, which="nx"):
        c, info, kind = self.need(slot)
        n = self._n(info, delta, which)
        out = (ctypes.c_double * max(1, n))()
        status, mark = self.call(function, c, out, ctypes.c_size_t(n))
        if self.check(function, status, mark):
            self.finite(function, out[:n])

    def op_get_states(self, slot, delta, values):
        self._get_array(slot, delta, "fmi2GetContinuousStates")

    def op_get_derivatives(self, slot, delta, values):
        self._get_array(slot, delta, "fmi2GetDerivatives")

    def op_get_nominals(self, slot, delta, values):
        self._get_array(slot, delta, "fmi2GetNominalsOfContinuousStates")

    def op_get_event_indicators(self, slot, delta, values):
        self._get_array(slot, delta, "fmi2GetEventIndicators", "nz")

    def op_do_step(self, slot, t, h, no_prior):
        c, info, kind = self.need(slot)
        start = self.slots[slot][4] if t == "cur" else t
        before = self.probe_state(slot)
        status, mark = self.call("fmi2DoStep", c, ctypes.c_double(start), ctypes.c_double(h), ctypes.c_int(no_prior))
        if self.check("fmi2DoStep", status, mark):
            self.slots[slot][4] = start + h
            # no fmi2OK with a state that is not finite
            self.read_state(slot, "fmi2DoStep", required=True)
        elif status == DISCARD:
            # not taken: stepFailed, at the step's start, the state as before and readable
            state = self.probe_state(slot)
            if state != "StepFailed":
                self.violate("discard-state:fmi2DoStep", f"fmi2DoStep returned fmi2Discard and left state {state}")
            last = ctypes.c_double(float("nan"))
            s2, mark2 = self.call("fmi2GetRealStatus", c, ctypes.c_int(2), ctypes.byref(last))
            self.check("fmi2GetRealStatus", s2, mark2)
            # the FMU accepts a communication point within 1e-9 (relative) of its time and keeps
            # its own: the fuzzer's bookkeeping may differ by as much
            expected = self.slots[slot][4]
            if s2 != OK or not abs(last.value - expected) <= 1e-9 * max(1.0, abs(expected), abs(h)):
                self.violate("discard-time:fmi2DoStep", f"after fmi2Discard fmi2LastSuccessfulTime is {last.value} "
                             f"(status {s2}), the step started at {self.slots[slot][4]}")
            self.read_state(slot, "fmi2DoStep(discard)", required=True)
        else:
            self.still_usable(slot, "fmi2DoStep", status, before)

    def op_get_state(self, slot, k):
        c, info, kind = self.need(slot)
        state = self.states[slot][k] or ctypes.c_void_p(None)
        status, mark = self.call("fmi2GetFMUstate", c, ctypes.byref(state))
        if self.check("fmi2GetFMUstate", status, mark) and state.value:
            self.states[slot][k] = state

    def op_set_state(self, slot, k):
        c, info, kind = self.need(slot)
        if self.states[slot][k] is None:
            raise _Skip()
        status, mark = self.call("fmi2SetFMUstate", c, self.states[slot][k])
        self.check("fmi2SetFMUstate", status, mark)

    def op_free_state(self, slot, k):
        c, info, kind = self.need(slot)
        if self.states[slot][k] is None:
            raise _Skip()
        state = self.states[slot][k]
        status, mark = self.call("fmi2FreeFMUstate", c, ctypes.byref(state))
        self.check("fmi2FreeFMUstate", status, mark)
        self.states[slot][k] = None

    def op_serialize(self, slot, k, into, short):
        c, info, kind = self.need(slot)
        if self.states[slot][k] is None:
            raise _Skip()
        size = ctypes.c_size_t(0)
        status, mark = self.call("fmi2SerializedFMUstateSize", c, self.states[slot][k], ctypes.byref(size))
        if not self.check("fmi2SerializedFMUstateSize", status, mark):
            return
        if size.value > 1 << 28:
            self.violate("hugesize:fmi2SerializedFMUstateSize", f"serialized size {size.value}")
            return
        n = size.value - 1 if short and size.value > 0 else size.value
        buf = ctypes.create_string_buffer(max(1, n))
        status, mark = self.call("fmi2SerializeFMUstate", c, self.states[slot][k], buf, ctypes.c_size_t(n))
        if self.check("fmi2SerializeFMUstate", status, mark):
            self.serialized[into] = buf.raw[:n]

    def op_deserialize(self, slot, k, src, damage, at, mask):
        c, info, kind = self.need(slot)
        data = self.serialized[src]
        if data is None:
            raise _Skip()
        data = bytearray(data)
        if damage == "flip" and data:
            data[at % len(data)] ^= mask
        elif damage == "truncate":
            data = data[: at % (len(data) + 1)]
        elif damage == "extend":
            data += bytes([mask]) * (at % 64 + 1)
        elif damage == "zero" and data:
            p = at % len(data)
            data[p:p + 8] = bytes(len(data[p:p + 8]))
        buf = ctypes.create_string_buffer(bytes(data), max(1, len(data)))
        state = self.states[slot][k] or ctypes.c_void_p(None)
        status, mark = self.call("fmi2DeSerializeFMUstate", c, buf, ctypes.c_size_t(len(data)), ctypes.byref(state))
        if self.check("fmi2DeSerializeFMUstate", status, mark) and state.value:
            self.states[slot][k] = state

    def op_directional(self, slot, unknowns, knowns, dv, bad):
        c, info, kind = self.need(slot)
        reals = info["vars"]["Real"]
        u = [reals[i % len(reals)][0] for i in unknowns]
        k = [reals[i % len(reals)][0] for i in knowns]
        if bad:
            u[0] = BAD_VRS[0]
        uu = (ctypes.c_uint * len(u))(*u)
        kk = (ctypes.c_uint * len(k))(*k)
        dd = (ctypes.c_double * len(dv))(*dv)
        out = (ctypes.c_double * len(u))()
        before = self.probe_state(slot)
        status, mark = self.call("fmi2GetDirectionalDerivative", c, uu, ctypes.c_size_t(len(u)), kk,
                                 ctypes.c_size_t(len(k)), dd, out)
        if self.check("fmi2GetDirectionalDerivative", status, mark):
            self.finite("fmi2GetDirectionalDerivative", out[:len(u)])
        self.still_usable(slot, "fmi2GetDirectionalDerivative", status, before)


class _Skip(Exception):
    pass


def _child(fmus, seqs, conn):
    # the FMU's Rust panic hook writes to stderr: keep the parent's output readable
    devnull = os.open(os.devnull, os.O_WRONLY)
    os.dup2(devnull, 2)
    try:
        import resource
        limit = 3 << 30
        resource.setrlimit(resource.RLIMIT_AS, (limit, limit))
    except (ImportError, ValueError, OSError):
        pass
    runner = Runner(fmus)
    for k, seq in enumerate(seqs):
        conn.send(("start", k))
        conn.send(("done", k, runner.run(seq), len(seq)))
    conn.send(("end",))
    conn.close()


def run_batch(fmus, seqs, timeout):
    """Runs the sequences in one child. Returns (per-sequence violation lists or None, calls, crash, hang)
    where crash/hang name the sequence index that was running."""
    ctx = multiprocessing.get_context("fork")
    parent, child = ctx.Pipe(duplex=False)
    p = ctx.Process(target=_child, args=(fmus, seqs, child))
    p.start()
    child.close()
    results = [None] * len(seqs)
    running, calls, deadline = None, 0, time.monotonic() + timeout
    crash = hang = None
    while True:
        left = deadline - time.monotonic()
        if left <= 0:
            hang = running if running is not None else 0
            os.kill(p.pid, signal.SIGKILL)
            p.join()
            break
        if not parent.poll(min(left, 1.0)):
            continue
        try:
            msg = parent.recv()
        except (EOFError, OSError):
            p.join()
            crash = (running, p.exitcode)
            break
        if msg[0] == "start":
            running = msg[1]
        elif msg[0] == "done":
            results[msg[1]] = msg[2]
            calls += msg[3]
            running = None
        else:
            p.join()
            break
    parent.close()
    return results, calls, crash, hang


def outcome_keys(fmus, seq, timeout):
    """The set of violation keys of one sequence run alone (crash and hang included)."""
    results, _, crash, hang = run_batch(fmus, [seq], timeout)
    if crash is not None:
        return {f"crash:signal {-crash[1] if crash[1] and crash[1] < 0 else crash[1]}"}
    if hang is not None:
        return {"hang"}
    return {key for key, _, _ in results[0]}


def shrink(fmus, seq, key, timeout, budget):
    """Removes calls (chunks, then one at a time) while the violation `key` stays."""
    t_end = time.monotonic() + budget
    chunk = max(1, len(seq) // 2)
    while chunk >= 1 and time.monotonic() < t_end:
        i, changed = 0, False
        while i < len(seq) and time.monotonic() < t_end:
            trial = seq[:i] + seq[i + chunk:]
            if trial and key in outcome_keys(fmus, trial, timeout):
                seq, changed = trial, True
            else:
                i += chunk
        if not changed:
            chunk //= 2
    return seq


def annotate(fmus, seq, call):
    """The variable names a call's value references pick (as the child resolves them)."""
    fi = {}
    for c in seq:
        if c[0] == "instantiate":
            fi[c[1]] = c[2]
        if c is call:
            break
    if call[0] in ("set_real", "get_real", "set_input_derivatives", "get_output_derivatives") and call[1] in fi:
        pool = fmus[fi[call[1]]]["vars"]["Real"]
        names = [str(v) if tag == "bad" else pool[v % len(pool)][3] for tag, v in call[2]]
        return "   # " + ", ".join(names)
    if call[0] == "directional" and call[1] in fi:
        pool = fmus[fi[call[1]]]["vars"]["Real"]
        return "   # d(" + ", ".join(pool[i % len(pool)][3] for i in call[2]) + ") / d(" + ", ".join(
            pool[i % len(pool)][3] for i in call[3]) + ")"
    return ""


def fmt_call(call):
    return json.dumps(call, default=str).replace("NaN", "nan").replace("Infinity", "inf")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--seconds", type=float, default=60)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--fmu", nargs="*", default=[])
    ap.add_argument("--build-dir", default=None, help="where FMUs are built when --fmu is not given")
    ap.add_argument("--batch", type=int, default=20, help="sequences per child process")
    ap.add_argument("--length", type=int, default=40, help="random calls per sequence (at most)")
    ap.add_argument("--timeout", type=float, default=10.0, help="seconds per batch before it counts as a hang")
    ap.add_argument("--shrink-seconds", type=float, default=30.0, help="time for shrinking each distinct violation")
    args = ap.parse_args(argv)

    work = Path(tempfile.mkdtemp(prefix="fmi-fuzz-"))
    try:
        paths = args.fmu or build_fmus(args.build_dir or work / "fmus")
        fmus = [describe(p, work / "extract") for p in paths]
        rng = random.Random(args.seed)
        runs = calls = crashes = hangs = 0
        distinct = {}  # key -> (sequence, message)
        t_end = time.monotonic() + args.seconds
        while time.monotonic() < t_end:
            seqs = [random_sequence(rng, fmus, rng.randrange(1, args.length + 1)) for _ in range(args.batch)]
            results, n_calls, crash, hang = run_batch(fmus, seqs, args.timeout)
            calls += n_calls
            runs += sum(r is not None for r in results)
            for seq, res in zip(seqs, results):
                for key, text, _ in res or []:
                    distinct.setdefault(key, (seq, text))
            if crash is not None or hang is not None:
                culprit = crash[0] if crash is not None else hang
                culprit = culprit if culprit is not None else 0
                seq = seqs[culprit]
                keys = outcome_keys(fmus, seq, args.timeout)
                runs += 1
                for key in keys:
                    if key.startswith("crash"):
                        crashes += 1
                    elif key == "hang":
                        hangs += 1
                    distinct.setdefault(key, (seq, key))
                if not keys:
                    # only in company: count it as the batch saw it
                    key = "crash:batch" if crash is not None else "hang"
                    crashes += crash is not None
                    hangs += hang is not None
                    distinct.setdefault(key, (seq, key))
        violations = {k: v for k, v in distinct.items()}
        print(f"runs {runs}  calls {calls}  crashes {crashes}  hangs {hangs}  "
              f"oracle violations {len([k for k in violations if not k.startswith(('crash', 'hang'))])} distinct")
        for key, (seq, text) in sorted(violations.items()):
            small = shrink(fmus, seq, key, min(args.timeout, 5.0), args.shrink_seconds)
            print(f"\nVIOLATION {key}: {text}\n  minimal reproducer ({len(small)} calls, FMUs {[Path(f['path']).name for f in fmus]}):")
            for call in small:
                print("    " + fmt_call(call) + annotate(fmus, small, call))
        sys.stdout.flush()
        return 1 if violations else 0
    finally:
        shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    sys.exit(main())
