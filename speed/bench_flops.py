"""Floating-point operations of one control step of the batched physics kernel, per vehicle,
and how close the kernel runs to one core's peak.

    python speed/bench_flops.py                       # every part and the summary (~20 s)
    python speed/bench_flops.py --part count [--steps 324]
    python speed/bench_flops.py --part trace [--warm 20] [--trace-steps 12] [--trace-stride 9]
    python speed/bench_flops.py --part time [--batch 64] [--block 100] [--rounds 11]
    python speed/bench_flops.py --part peak

The kernel is ``hyperloop_env.physics.model.control_step`` (``control_step_serial`` /
``control_step_batch`` run it per row) in the default scenario, ``ModelParams()``:
paper-1000-straight, levitation actuators, 2 RK4 substeps per 1 ms control step; seed 0,
constant nominal currents, as ``speed/bench_kernel.py``.

count   The source count. ``control_step``'s Python source (``py_func``) and every compiled
        function it calls run on arrays of a float type that counts each +, -, x, /,
        comparison and conversion, with a ``math`` that counts each call, for ``--steps``
        control steps of one vehicle from reset (324: three 30 m spans at 1000 km/h; which
        span slots the footprints touch repeats every span). Every step starts from the
        compiled kernel's state and its result is compared with the compiled kernel's, bit
        for bit. Prints the operations per control step (mean, min, max) by kind and by
        function.
trace   The machine-code count, independent of the source: a child process runs the
        compiled serial kernel on a batch of one; this process single-steps it with ptrace
        (Linux x86-64, root or ptrace rights; ``objdump`` from binutils) through
        ``--trace-steps`` control steps, one every ``--trace-stride`` after ``--warm``
        untraced ones (the steps in between run the single-vehicle kernel, untraced). Every
        executed instruction is counted and disassembled, so each loop body counts by its
        trip count as it ran; double-precision arithmetic is counted per lane (an FMA is 2
        FLOPs), split into the compiled kernel and each library function it calls. The
        source count of the same steps is printed beside it. (``perf stat`` would do this
        with hardware counters where a machine exposes them.)
time    Thread CPU seconds per vehicle-step of the serial kernel on one thread (batch
        ``--batch``, ``--rounds`` blocks of ``--block`` steps; minimum and median; CPU time
        leaves out the time another process holds the core), and cycles per vehicle-step at
        the clock measured right before each block.
peak    The core's clock from a chain of dependent 1-cycle integer operations (add, xor),
        and at that clock: the latency of a double multiply and add, the cost of a scalar
        and of a vectorised division, and of one atan, log1p, cos and exp call, in compiled
        loops; single-threaded OpenBLAS dgemm (an attainable peak) in FLOPs per cycle.

With every part, the summary: FLOPs per vehicle-step / time per vehicle-step = achieved
FLOP/s and FLOPs per cycle, against the core's peak (2 FMA units x 8 doubles x 2 FLOPs per
cycle, AVX-512: an assumption that dgemm above 16 FLOPs per cycle supports), the scalar FMA
peak and dgemm; instructions per cycle; the cycles the divisions and library calls take at
their measured cost; and a model of a structure-of-arrays kernel vectorised across the batch.
Minimums are the figures to quote on a loaded machine.
"""

from __future__ import annotations

import argparse
import collections
import ctypes
import json
import math
import os
import re
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numba
import numpy as np

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO))

from hyperloop_env.physics import (  # noqa: E402
    BatchSimulator,
    ModelParams,
    guideway,
    irregularity,
    magnets,
    model,
    track,
    vehicle,
)

TRANSCENDENTAL = ("atan", "log1p", "cos", "sin", "exp", "log", "sqrt")


def make_batch(n: int) -> tuple[BatchSimulator, np.ndarray]:
    b = BatchSimulator(ModelParams(), n=n)
    b.reset(list(range(n)))
    cmd = b.full_commands(np.repeat(b.nominal_current_A[:, None], 4, axis=1)).copy()
    return b, cmd


# ---- count: the kernel's source executed on counting floats ---------------------------

COUNTS: collections.Counter = collections.Counter()
STACK = ["control_step"]


def _v(o: object) -> float:
    return o.v if isinstance(o, CF) else float(o)


def _tick(op: str) -> None:
    COUNTS[STACK[-1], op] += 1


class CF:
    """A float that counts the operations done on it (into COUNTS, by function)."""

    __slots__ = ("v",)
    __array_ufunc__ = None  # numpy scalars defer to the reflected methods
    __hash__ = None

    def __init__(self, v: float) -> None:
        self.v = v

    def __add__(self, o):  # noqa: ANN001, ANN204
        _tick("add")
        return CF(self.v + _v(o))

    def __radd__(self, o):  # noqa: ANN001, ANN204
        _tick("add")
        return CF(_v(o) + self.v)

    def __sub__(self, o):  # noqa: ANN001, ANN204
        _tick("sub")
        return CF(self.v - _v(o))

    def __rsub__(self, o):  # noqa: ANN001, ANN204
        _tick("sub")
        return CF(_v(o) - self.v)

    def __mul__(self, o):  # noqa: ANN001, ANN204
        _tick("mul")
        return CF(self.v * _v(o))

    def __rmul__(self, o):  # noqa: ANN001, ANN204
        _tick("mul")
        return CF(_v(o) * self.v)

    def __truediv__(self, o):  # noqa: ANN001, ANN204
        _tick("div")
        return CF(self.v / _v(o))

    def __rtruediv__(self, o):  # noqa: ANN001, ANN204
        _tick("div")
        return CF(_v(o) / self.v)

    def __neg__(self):  # noqa: ANN204
        _tick("neg")
        return CF(-self.v)

    def __abs__(self):  # noqa: ANN204
        _tick("abs")
        return CF(abs(self.v))

    def _cmp(self, o, f):  # noqa: ANN001, ANN202
        _tick("cmp")
        return f(self.v, _v(o))

    def __lt__(self, o):  # noqa: ANN001, ANN204
        return self._cmp(o, float.__lt__)

    def __le__(self, o):  # noqa: ANN001, ANN204
        return self._cmp(o, float.__le__)

    def __gt__(self, o):  # noqa: ANN001, ANN204
        return self._cmp(o, float.__gt__)

    def __ge__(self, o):  # noqa: ANN001, ANN204
        return self._cmp(o, float.__ge__)

    def __eq__(self, o):  # noqa: ANN001, ANN204
        return self._cmp(o, float.__eq__)

    def __ne__(self, o):  # noqa: ANN001, ANN204
        return self._cmp(o, float.__ne__)

    def __int__(self) -> int:
        _tick("cvt")
        return int(self.v)

    def __float__(self) -> float:
        return self.v


class CountingMath:
    """``math`` for the replay: counts every call by name."""

    def __getattr__(self, name: str):  # noqa: ANN204
        f = getattr(math, name)
        if not callable(f):
            return f

        def call(*args):  # noqa: ANN002, ANN202
            _tick(name)
            r = f(*(_v(a) for a in args))
            return CF(r) if isinstance(r, float) else r

        return call


LABELLED = (
    "control_step",
    "rhs_loaded",
    "stage_positions",
    "stage_currents",
    "_update_ring",
    "_measure",
)


def _labelled(fn, label: str):  # noqa: ANN001, ANN202
    def run(*args):  # noqa: ANN002, ANN202
        STACK.append(label)
        try:
            return fn(*args)
        finally:
            STACK.pop()

    return run


class Replay:
    """The physics modules with their compiled functions swapped for their Python source
    (and ``math`` for CountingMath) while in the ``with`` block."""

    MODS = (model, vehicle, guideway, magnets, track, irregularity)

    def __enter__(self) -> Replay:
        self.saved = []
        cm = CountingMath()
        for mod in self.MODS:
            for name, obj in list(vars(mod).items()):
                if isinstance(obj, numba.core.dispatcher.Dispatcher):
                    self.saved.append((mod, name, obj))
                    fn = obj.py_func
                    setattr(mod, name, _labelled(fn, name) if name in LABELLED else fn)
            self.saved.append((mod, "math", mod.math))
            mod.math = cm
        return self

    def __exit__(self, *exc: object) -> None:
        for mod, name, obj in self.saved:
            setattr(mod, name, obj)


def _cf(a: np.ndarray) -> np.ndarray:
    out = np.empty(a.shape, dtype=object)
    flat = out.reshape(-1)
    for i, x in enumerate(a.reshape(-1)):
        flat[i] = CF(float(x))
    return out


def _bits(a: np.ndarray) -> np.ndarray:
    return np.array([_v(x) for x in a.reshape(-1)]).view(np.int64)


def source_count(n_steps: int) -> tuple[list[collections.Counter], int]:
    """Counted operations of each of ``n_steps`` control steps of vehicle 0 from reset,
    keyed (function, op); and the number of steps whose replayed state and record differ
    from the compiled kernel's in any bit."""
    b, cmd = make_batch(1)
    P = _cf(b.P[0])
    irr = _cf(b.IRR[0])
    icmd = _cf(cmd[0])
    work = _cf(b.WORK[0])
    tl = _cf(b.TL[0])
    uo = _cf(b.UO[0])
    meas = _cf(b.MEAS[0])
    per_step = []
    differ = 0
    with Replay():
        step = model.control_step  # its Python source, labelled
        for _ in range(n_steps):
            y = _cf(b.Y[0])
            aux = _cf(b.AUX[0])
            spans = b.SPANS[0].copy()
            COUNTS.clear()
            step(P, y, aux, irr, icmd, meas, work, tl, uo, spans)
            per_step.append(collections.Counter(COUNTS))
            b.step_full(cmd, parallel=False)
            if not (
                np.array_equal(_bits(y), b.Y[0].view(np.int64))
                and np.array_equal(_bits(aux), b.AUX[0].view(np.int64))
                and np.array_equal(_bits(meas), b.MEAS[0].view(np.int64))
            ):
                differ += 1
    return per_step, differ


def by_op(c: collections.Counter) -> collections.Counter:
    out: collections.Counter = collections.Counter()
    for (_, op), n in c.items():
        out[op] += n
    return out


def flops_of(ops: collections.Counter) -> int:
    return ops["add"] + ops["sub"] + ops["mul"] + ops["div"] + ops["sqrt"] + 2 * ops["fma"]


def report_count(per_step: list[collections.Counter]) -> dict:
    ops = [by_op(c) for c in per_step]
    kinds = ["add", "sub", "mul", "div", "fma", *TRANSCENDENTAL, "floor"]
    other = ["cmp", "neg", "abs", "cvt", "isfinite"]
    print(f"source count: control steps 0..{len(per_step) - 1} of one vehicle from reset")
    print("  per control step        mean      min      max")
    for k in [*kinds, "FLOPs", *other]:
        v = [flops_of(o) if k == "FLOPs" else o[k] for o in ops]
        if k == "fma" or max(v) > 0:
            print(f"  {k:18s} {statistics.fmean(v):9.1f} {min(v):8d} {max(v):8d}")
    print("  by function (mean per control step): add+sub / mul / div / calls")
    funcs = sorted({f for c in per_step for f, _ in c})
    for f in funcs:
        m = {
            op: statistics.fmean(c[f, op] for c in per_step)
            for op in ("add", "sub", "mul", "div", *TRANSCENDENTAL)
        }
        calls = " ".join(f"{op} {m[op]:.1f}" for op in TRANSCENDENTAL if m[op])
        print(
            f"    {f:16s} {m['add'] + m['sub']:7.1f} / {m['mul']:7.1f} / {m['div']:6.1f}  {calls}"
        )
    mode = collections.Counter(flops_of(o) for o in ops).most_common(1)[0]
    print(f"  most frequent FLOPs per step: {mode[0]} ({mode[1]} of {len(ops)} steps)")
    return {
        "flops": statistics.fmean(flops_of(o) for o in ops),
        "ops": {k: statistics.fmean(o[k] for o in ops) for k in kinds + other},
    }


# ---- trace: single-step the compiled kernel with ptrace --------------------------------

PTRACE_PEEKTEXT, PTRACE_PEEKUSER, PTRACE_POKETEXT, PTRACE_POKEUSER = 1, 3, 4, 6
PTRACE_CONT, PTRACE_SINGLESTEP, PTRACE_ATTACH, PTRACE_DETACH = 7, 9, 16, 17
OFF_RIP, OFF_RSP = 16 * 8, 19 * 8  # struct user_regs_struct, x86-64
MASK64 = (1 << 64) - 1
LIB_NAMES = (
    "atan",
    "numba_log1p",
    "log1p",
    "cos",
    "sin",
    "exp",
    "log",
    "sqrt",
    "floor",
    "memset",
    "memcpy",
    "memmove",
)


def trace_child(warm: int, steps: int, stride: int) -> None:
    """Child side of ``trace``: ``warm`` steps, then ``steps`` times ``stride - 1`` steps of
    the single-vehicle kernel ``control_step`` (not traced) and one of ``control_step_serial``
    (traced; the same arithmetic)."""
    import llvmlite.binding as ll

    numba.set_num_threads(1)
    b, cmd = make_batch(1)
    rows = (b.P[0], b.Y[0], b.AUX[0], b.IRR[0], cmd[0], b.MEAS[0], b.WORK[0], b.TL[0])
    rows += (b.UO[0], b.SPANS[0])
    for _ in range(warm):
        model.control_step(*rows)
    b.step_full(cmd, parallel=False)  # compiled and loaded before the trace
    f = model.control_step_serial
    cres = f.overloads[f.signatures[0]]
    addr = cres.library.get_pointer_to_function(cres.fndesc.llvm_func_name)
    syms = {n: ll.address_of_symbol(n) for n in LIB_NAMES}
    print(json.dumps({"addr": addr, "syms": syms}), flush=True)
    sys.stdin.readline()
    for _ in range(steps):
        for _ in range(stride - 1):
            model.control_step(*rows)
        b.step_full(cmd, parallel=False)
    print("done", flush=True)
    sys.stdin.readline()


class Tracer:
    def __init__(self, pid: int) -> None:
        self.pid = pid
        self.libc = ctypes.CDLL(None, use_errno=True)
        self.libc.ptrace.argtypes = [ctypes.c_long, ctypes.c_long, ctypes.c_void_p, ctypes.c_void_p]
        self.libc.ptrace.restype = ctypes.c_long

    def call(self, req: int, addr: int = 0, data: int = 0) -> int:
        ctypes.set_errno(0)
        r = self.libc.ptrace(req, self.pid, addr, data)
        if r == -1 and ctypes.get_errno():
            raise OSError(ctypes.get_errno(), f"ptrace({req}) failed")
        return r & MASK64

    def wait_stop(self) -> None:
        _, status = os.waitpid(self.pid, 0)
        if not os.WIFSTOPPED(status):
            raise RuntimeError(f"traced child did not stop (status {status:#x})")

    def one_call(self, addr: int) -> list[int]:
        """Run to the breakpoint at ``addr``; single-step until the function returns."""
        word = self.call(PTRACE_PEEKTEXT, addr)
        self.call(PTRACE_POKETEXT, addr, (word & ~0xFF) | 0xCC)
        self.call(PTRACE_CONT)
        self.wait_stop()
        if self.call(PTRACE_PEEKUSER, OFF_RIP) != addr + 1:
            raise RuntimeError("stopped elsewhere than at the kernel's entry")
        self.call(PTRACE_POKETEXT, addr, word)
        self.call(PTRACE_POKEUSER, OFF_RIP, addr)
        sp0 = self.call(PTRACE_PEEKUSER, OFF_RSP)
        ret = self.call(PTRACE_PEEKTEXT, sp0)
        ptrace, pid = self.libc.ptrace, self.pid
        pcs = [addr]
        while True:
            ptrace(PTRACE_SINGLESTEP, pid, 0, 0)
            os.waitpid(pid, 0)
            rip = ptrace(PTRACE_PEEKUSER, pid, OFF_RIP, 0) & MASK64
            if rip == ret and self.call(PTRACE_PEEKUSER, OFF_RSP) > sp0:
                return pcs
            pcs.append(rip)


def _maps(pid: int) -> list[tuple[int, int, str]]:
    out = []
    for line in Path(f"/proc/{pid}/maps").read_text().splitlines():
        f = line.split()
        lo, hi = (int(x, 16) for x in f[0].split("-"))
        out.append((lo, hi, f[5] if len(f) > 5 else ""))
    return out


def _region(pc: int, maps: list[tuple[int, int, str]]) -> tuple[str, int]:
    for lo, hi, path in maps:
        if lo <= pc < hi:
            return (Path(path).name if path else "[jit]"), hi
    return "?", pc + 16


def _disassemble(pid: int, pcs: set[int], maps: list) -> dict[int, tuple[str, str]]:
    """{pc: (mnemonic, operands)} of every executed instruction, from the process memory."""
    todo = sorted(pcs)
    out: dict[int, tuple[str, str]] = {}
    line_re = re.compile(r"^\s*([0-9a-f]+):\t(?:[0-9a-f]{2} )+\s*\t(.*)$")
    prefixes = {"rep", "repz", "repnz", "lock", "notrack", "bnd", "data16", "cs", "ds"}
    with open(f"/proc/{pid}/mem", "rb", buffering=0) as mem, tempfile.TemporaryDirectory() as d:
        for _ in range(50):
            missing = [pc for pc in todo if pc not in out]
            if not missing:
                break
            groups, start, prev = [], missing[0], missing[0]
            for pc in missing[1:]:
                if pc - prev > 512:
                    groups.append((start, prev))
                    start = pc
                prev = pc
            groups.append((start, prev))
            for lo, hi in groups:
                _, end = _region(lo, maps)
                mem.seek(lo)
                data = mem.read(min(hi + 16, end) - lo)
                fn = Path(d) / "code.bin"
                fn.write_bytes(data)
                dis = subprocess.run(
                    ["objdump", "-D", "-b", "binary", "-m", "i386:x86-64", "--insn-width=16"]
                    + [f"--adjust-vma={lo:#x}", str(fn)],
                    check=True,
                    capture_output=True,
                    text=True,
                ).stdout
                for line in dis.splitlines():
                    m = line_re.match(line)
                    if not m:
                        continue
                    pc = int(m.group(1), 16)
                    if pc in pcs and pc not in out:
                        toks = m.group(2).split()
                        while toks and toks[0] in prefixes:
                            toks = toks[1:]
                        if toks:
                            out[pc] = (toks[0], " ".join(toks[1:]))
                if missing[0] not in out:  # desynchronised sweep: restart at that pc
                    out.setdefault(missing[0], ("(undecoded)", ""))
    return out


FP_RE = re.compile(r"^v?(add|sub|mul|div|sqrt|min|max)(s|p)(d|s)$")
FMA_RE = re.compile(r"^vf(n?)m(add|sub|addsub|subadd)(132|213|231)(s|p)(d|s)$")


def classify(mn: str, ops: str) -> tuple[str, int]:
    """(category, lanes): arithmetic categories are add/mul/div/sqrt/minmax/fma with
    their lane count; the rest cmp, cvt, round, logic, fpmove, branch, other."""
    m = FMA_RE.match(mn)
    if m:
        return "fma" + ("" if m.group(5) == "d" else "_sp"), _lanes(m.group(4), m.group(5), ops)
    m = FP_RE.match(mn)
    if m:
        kind = {"sub": "add", "min": "minmax", "max": "minmax"}.get(m.group(1), m.group(1))
        return kind + ("" if m.group(3) == "d" else "_sp"), _lanes(m.group(2), m.group(3), ops)
    if re.match(r"^v?u?comis[ds]$|^v?cmp\w*[sp][ds]$", mn):
        return "cmp", 1
    if re.match(r"^v?cvt", mn):
        return "cvt", 1
    if re.match(r"^v?(round|rndscale)[sp][ds]$", mn):
        return "round", 1
    if re.match(r"^v?(and|andn|or|xor)p[ds]$", mn):
        return "logic", 1
    if re.match(r"^v?(mov|broadcast|unpck|shuf|perm|blend|insert|extract|gather)", mn):
        return "fpmove" if "mm" in ops else "other", 1
    if mn.startswith("j") or mn.startswith("call") or mn.startswith("ret"):
        return "branch", 1
    return "other", 1


def _lanes(sp: str, prec: str, ops: str) -> int:
    if sp == "s":
        return 1
    width = 512 if "%zmm" in ops else 256 if "%ymm" in ops else 128
    return width // (64 if prec == "d" else 32)


def traced_steps(warm: int, steps: int, stride: int) -> list[int]:
    """Indices (from reset, 0-based) of the traced control steps."""
    return [warm + 1 + k * stride + stride - 1 for k in range(steps)]


def machine_count(warm: int, steps: int, stride: int) -> list[dict]:
    """Per traced control step: instruction and FP counts in the kernel and per libm call."""
    child = subprocess.Popen(
        [sys.executable, str(Path(__file__).resolve()), "--trace-child"]
        + [f"--warm={warm}", f"--trace-steps={steps}", f"--trace-stride={stride}"],
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        text=True,
    )
    try:
        info = json.loads(child.stdout.readline())
        names = {v: k for k, v in info["syms"].items() if v}
        tr = Tracer(child.pid)
        tr.call(PTRACE_ATTACH)
        tr.wait_stop()
        child.stdin.write("go\n")
        child.stdin.flush()
        traces = [tr.one_call(info["addr"]) for _ in range(steps)]
        maps = _maps(child.pid)
        dis = _disassemble(child.pid, {pc for t in traces for pc in t}, maps)
        tr.call(PTRACE_DETACH)
        child.stdout.readline()
        child.stdin.write("quit\n")
        child.stdin.flush()
        child.wait()
    finally:
        if child.poll() is None:
            child.kill()
            child.wait()
    region = {pc: _region(pc, maps)[0] for pc in dis}
    results = []
    for pcs in traces:
        res = {"instructions": len(pcs), "calls": collections.Counter(), "by": {}}
        label = "kernel"
        for pc in pcs:
            if region[pc] == "[jit]":
                label = "kernel"
            elif label == "kernel":  # entering a library function from the kernel
                label = names.get(pc, f"{region[pc]}+{pc:#x}")
                res["calls"][label] += 1
            mn, ops = dis[pc]
            cat, lanes = classify(mn, ops)
            c = res["by"].setdefault(label, collections.Counter())
            c["instructions"] += 1
            c[cat] += lanes
            c[cat + ":insn"] += 1
            if "(" in ops and not mn.startswith(("lea", "nop")):
                c["memory"] += 1
            if cat in ("add", "mul", "div", "sqrt", "minmax", "fma") and lanes > 1:
                c["packed:insn"] += 1
        results.append(res)
    return results


def fp_flops(c: collections.Counter) -> int:
    return c["add"] + c["mul"] + c["div"] + c["sqrt"] + 2 * c["fma"]


def report_trace(results: list[dict], steps: list[int], src: dict | None) -> dict:
    print(
        f"machine-code count: control steps {', '.join(map(str, steps))} of one "
        "vehicle from reset, every executed instruction (ptrace single-step, objdump)"
    )
    cats = ["add", "mul", "div", "fma", "sqrt", "minmax", "cmp", "cvt", "round", "logic"]
    ratios = []
    for i, r in zip(steps, results, strict=True):
        k = r["by"]["kernel"]
        libs = sum(v["instructions"] for n, v in r["by"].items() if n != "kernel")
        line = " ".join(f"{c} {k[c]}" for c in cats if k[c] or c == "fma")
        calls = " ".join(f"{n} {v}" for n, v in sorted(r["calls"].items()))
        print(
            f"  step {i}: {r['instructions']} instructions ({k['instructions']} kernel, "
            f"{libs} in library calls); kernel FLOPs {fp_flops(k)} [{line}; packed "
            f"{k['packed:insn']} instr.]; calls: {calls}"
        )
        if src is not None:
            o = collections.Counter(src["per_step_ops"][i])
            ratios.append(fp_flops(k) / flops_of(o))
            print(
                f"          source count: FLOPs {flops_of(o)} [add {o['add'] + o['sub']} "
                f"mul {o['mul']} div {o['div']}]; calls: "
                + " ".join(f"{n} {o[n]}" for n in TRANSCENDENTAL if o[n])
                + f"; machine / source FLOPs {ratios[-1]:.3f}"
            )
    agg: dict[str, collections.Counter] = {}
    calls: collections.Counter = collections.Counter()
    for r in results:
        calls.update(r["calls"])
        for n, c in r["by"].items():
            agg.setdefault(n, collections.Counter()).update(c)
    n = len(results)
    print(f"  mean per control step over the {n} traced steps:")
    for name, c in sorted(agg.items(), key=lambda kv: -kv[1]["instructions"]):
        each = (
            f" in {calls[name] / n:.1f} calls ({c['instructions'] / calls[name]:.0f} each)"
            if calls[name]
            else ""
        )
        print(
            f"    {name:12s} {c['instructions'] / n:7.0f} instructions"
            + each
            + f"; FLOPs {fp_flops(c) / n:.0f} (add {c['add'] / n:.0f}, mul {c['mul'] / n:.0f}, "
            f"div {c['div'] / n:.0f}, fma {c['fma'] / n:.0f}, sqrt {c['sqrt'] / n:.0f}); "
            f"memory operands {c['memory'] / n:.0f}; branches {c['branch'] / n:.0f}; "
            f"packed arithmetic instr. {c['packed:insn'] / n:.0f}"
        )
    if ratios:
        print(
            f"  machine / source FLOPs on the same steps: mean {statistics.fmean(ratios):.3f} "
            f"[{min(ratios):.3f}, {max(ratios):.3f}]"
        )
    k = agg["kernel"]
    return {
        "instructions": statistics.fmean(r["instructions"] for r in results),
        "kernel_flops": fp_flops(k) / n,
        "kernel_div": k["div"] / n,
        "kernel_instructions": k["instructions"] / n,
        "lib_flops": sum(fp_flops(c) for name, c in agg.items() if name != "kernel") / n,
        "calls": {name: v / n for name, v in calls.items()},
        "ratio": statistics.fmean(ratios) if ratios else None,
    }


# ---- time and peak ----------------------------------------------------------------------


def kernel_time(batch: int, block: int, rounds: int) -> dict:
    """Thread CPU time per vehicle-step of the serial kernel, each block right after a clock
    measurement (the clock drifts on a shared machine): seconds and cycles per vehicle-step."""
    numba.set_num_threads(1)
    b, cmd = make_batch(batch)
    for _ in range(20):
        b.step_full(cmd, parallel=False)
    clock_hz()
    per, wall, cyc, clk = [], [], [], []
    for _ in range(rounds):
        f = clock_hz()
        c, w = time.thread_time(), time.perf_counter()
        for _ in range(block):
            b.step_full(cmd, parallel=False)
        per.append((time.thread_time() - c) / (batch * block))
        wall.append((time.perf_counter() - w) / (batch * block))
        cyc.append(per[-1] * f)
        clk.append(f)
    ok = bool(np.isfinite(b.Y).all())
    print(
        f"kernel time: control_step_serial, one thread, batch {batch}, {rounds} blocks of "
        f"{block} steps (steps 20..{20 + rounds * block - 1}): per vehicle-step "
        f"{min(per) * 1e6:.3f} us (min), {statistics.median(per) * 1e6:.3f} us (median), "
        f"thread CPU time (wall min {min(wall) * 1e6:.3f} us); {1 / min(per):,.0f} "
        f"vehicle-steps/s; at the clock measured before each block ({min(clk) / 1e9:.2f}-"
        f"{max(clk) / 1e9:.2f} GHz) {min(cyc):.0f} cycles (min), {statistics.median(cyc):.0f} "
        f"(median); state finite: {ok}"
    )
    return {
        "t_min": min(per),
        "t_med": statistics.median(per),
        "cyc_min": min(cyc),
        "cyc_med": statistics.median(cyc),
        "clk": statistics.median(clk),
    }


def clock_hz(n: int = 2_000_000, reps: int = 3) -> float:
    """The core's clock [Hz] now: a chain of dependent 1-cycle integer operations."""
    return 2 * n / _best(_clock_chain, n, 1, 3, reps=reps)


@numba.njit(cache=False)
def _clock_chain(n: int, x: int, y: int) -> int:
    for i in range(n):
        x = (x + y) ^ i  # two dependent 1-cycle integer operations per iteration
    return x


@numba.njit(cache=False)
def _mul_chain(n: int, x: float, y: float) -> float:
    for _ in range(n):
        x = x * y
    return x


@numba.njit(cache=False)
def _add_chain(n: int, x: float, y: float) -> float:
    for _ in range(n):
        x = x + y
    return x


@numba.njit(cache=False, error_model="numpy")
def _div_scalar(a: np.ndarray, b: np.ndarray) -> float:
    s0 = s1 = s2 = s3 = 0.0
    n = a.shape[0] // 4
    for i in range(n):
        s0 += a[i] / b[i]
        s1 += a[i + n] / b[i + n]
        s2 += a[i + 2 * n] / b[i + 2 * n]
        s3 += a[i + 3 * n] / b[i + 3 * n]
    return s0 + s1 + s2 + s3


@numba.njit(cache=False, error_model="numpy")
def _div_vector(a: np.ndarray, b: np.ndarray, out: np.ndarray) -> None:
    for i in range(a.shape[0]):
        out[i] = a[i] / b[i]


@numba.njit(cache=False)
def _atan(x: np.ndarray) -> float:
    s = 0.0
    for i in range(x.shape[0]):
        s += math.atan(x[i])
    return s


@numba.njit(cache=False)
def _log1p(x: np.ndarray) -> float:
    s = 0.0
    for i in range(x.shape[0]):
        s += math.log1p(x[i])
    return s


@numba.njit(cache=False)
def _cos(x: np.ndarray) -> float:
    s = 0.0
    for i in range(x.shape[0]):
        s += math.cos(x[i])
    return s


@numba.njit(cache=False)
def _exp(x: np.ndarray) -> float:
    s = 0.0
    for i in range(x.shape[0]):
        s += math.exp(x[i])
    return s


def _best(fn, *args, reps: int = 11) -> float:  # noqa: ANN001
    fn(*args)
    best = math.inf
    for _ in range(reps):
        t = time.thread_time()
        fn(*args)
        best = min(best, time.thread_time() - t)
    return best


def _asm_of(fn) -> str:  # noqa: ANN001
    return fn.inspect_asm(fn.signatures[0])


DGEMM = """
import time, numpy as np
n = {n}
a = np.random.default_rng(0).random((n, n)); b = a.T.copy()
a @ b
best = min((lambda t: (a @ b, time.perf_counter() - t)[1])(time.perf_counter()) for _ in range(5))
print(2 * n**3 / best)
"""


def peak() -> dict:
    numba.set_num_threads(1)
    n = 20_000_000
    t_clk = _best(_clock_chain, n, 1, 3)
    clk_scalar = re.search(r"%[xyz]mm", _asm_of(_clock_chain)) is None
    freq = 2 * n / t_clk
    t_mul = _best(_mul_chain, n, 1.0, 1.0)
    t_add = _best(_add_chain, n, 0.0, 0.0)
    f_fp = clock_hz()
    rng = np.random.default_rng(0)
    a = rng.random(4096) + 1.0
    bb = rng.random(4096) + 1.0
    out = np.empty_like(a)
    reps = 200

    def many(fn, *args):  # noqa: ANN001, ANN202
        for _ in range(reps):
            fn(*args)

    f_div = clock_hz()
    ts = _best(many, _div_scalar, a, bb) / (reps * a.size) * f_div
    tv = _best(many, _div_vector, a, bb, out) / (reps * a.size) * f_div
    a_div = _asm_of(_div_scalar)
    scal_ok = "vdivsd" in a_div and "vdivpd" not in a_div
    widths = re.findall(r"vdivpd\s+[^\n]*%([xyz]mm)", _asm_of(_div_vector))
    vec = max(widths, key=lambda w: "xyz".index(w[0])) if widths else "none"
    u = rng.uniform(-0.5, 0.5, 4096)
    th = rng.uniform(0.0, math.pi, 4096)
    f_lib = clock_hz()
    libm = {
        "atan": _best(many, _atan, u) / (reps * u.size) * f_lib,
        "log1p": _best(many, _log1p, u * u) / (reps * u.size) * f_lib,
        "cos": _best(many, _cos, th) / (reps * th.size) * f_lib,
        "exp": _best(many, _exp, -u * u) / (reps * u.size) * f_lib,
    }
    env = dict(os.environ, OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1", MKL_NUM_THREADS="1")
    f_gemm = clock_hz()
    gemm = float(
        subprocess.run(
            [sys.executable, "-c", DGEMM.format(n=1536)],
            env=env,
            check=True,
            capture_output=True,
            text=True,
        ).stdout
    )
    f_gemm = max(f_gemm, clock_hz())
    print(
        f"clock: dependent integer add + xor (1 cycle each) {t_clk / n * 1e9:.4f} ns per pair "
        f"-> {freq / 1e9:.2f} GHz (scalar code: {clk_scalar}); a dependent double multiply "
        f"takes {t_mul / n * freq:.2f} cycles, an add {t_add / n * freq:.2f} "
        f"(clock {f_fp / 1e9:.2f} GHz right after)"
    )
    print(
        f"division: scalar {ts:.2f} cycles each (vdivsd only: {scal_ok}); vectorised "
        f"(vdivpd {vec}) {tv:.2f} cycles per element (clock {f_div / 1e9:.2f} GHz)"
    )
    print(
        "libm in a compiled loop, cycles per call: "
        + ", ".join(f"{k} {v:.1f}" for k, v in libm.items())
        + f" (clock {f_lib / 1e9:.2f} GHz)"
    )
    print(
        f"dgemm 1536, OpenBLAS, one thread, best of 5: {gemm / 1e9:.1f} GFLOP/s "
        f"= {gemm / f_gemm:.1f} FLOPs per cycle at the higher clock measured around it "
        f"({f_gemm / 1e9:.2f} GHz)"
    )
    return {"freq": freq, "div_s": ts, "div_v": tv, "libm": libm, "gemm_fpc": gemm / f_gemm}


def summary(src: dict, trace: dict, tm: dict, pk: dict) -> None:
    t = tm["t_min"]
    cyc = tm["cyc_min"]
    fl_src = src["flops"]
    fl_mc = fl_src * trace["ratio"]
    print(
        "summary, per vehicle-step (time and cycles: the minima; FLOPs: the source count's "
        "mean over its steps, the machine count scaled by its machine / source ratio):"
    )
    print(
        f"  FLOPs: source {fl_src:.0f}, compiled kernel {fl_mc:.0f}, + {trace['lib_flops']:.0f}"
        f" inside {sum(trace['calls'].values()):.0f} library calls"
    )
    print(f"  time {t * 1e9:.0f} ns, {cyc:.0f} cycles")
    for name, fl in (("kernel", fl_mc), ("kernel + libm", fl_mc + trace["lib_flops"])):
        fpc = fl / cyc
        print(
            f"  achieved ({name}): {fl / t / 1e9:.2f} GFLOP/s, {fpc:.2f} FLOPs per cycle = "
            f"{fpc / 32:.1%} of the core's peak of 32 (2 FMA units x 8 doubles x 2), "
            f"{fpc / 4:.0%} of the scalar peak of 4 (2 scalar FMAs), {fpc / pk['gemm_fpc']:.1%}"
            f" of dgemm's {pk['gemm_fpc']:.1f}"
        )
    print(f"  instructions per cycle {trace['instructions'] / cyc:.2f} (traced steps' mean)")
    ndiv = trace["kernel_div"]
    div_c = ndiv * pk["div_s"]
    lib = {k: trace["calls"].get(k, 0.0) for k in pk["libm"]}
    lib_c = sum(lib[k] * pk["libm"][k] for k in lib)
    print(
        f"  divisions: {ndiv:.0f} x {pk['div_s']:.2f} cycles = {div_c:.0f} cycles "
        f"= {div_c / cyc:.0%} of the step (the divider's own floor)"
    )
    print(
        f"  library calls: {sum(lib.values()):.0f} at their cost in a loop = {lib_c:.0f} cycles "
        f"= {lib_c / cyc:.0%}"
    )
    # A structure-of-arrays kernel vectorised across the batch: divisions at the measured
    # vector cost per element; the other kernel instructions shared by `lanes` vehicles at
    # the IPC measured now; the library calls kept scalar (bit for bit).
    other = trace["kernel_instructions"] - ndiv
    ipc = trace["instructions"] / cyc
    lib_insn = trace["instructions"] - trace["kernel_instructions"]
    for lanes in (2, 4):
        issue = (other / lanes + lib_insn) / ipc
        floor = ndiv * pk["div_v"]
        est = max(floor, issue)
        print(
            f"  SoA across the batch, {lanes}x fewer kernel instructions other than divisions, "
            f"library calls scalar: issue {issue:.0f} cycles at the same IPC, divisions "
            f"{floor:.0f} -> {est:.0f} cycles: x{cyc / est:.2f}"
        )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--part", choices=("all", "count", "trace", "time", "peak"), default="all")
    ap.add_argument(
        "--steps", type=int, default=324, help="steps of the source count (324: three spans)"
    )
    ap.add_argument("--warm", type=int, default=20, help="untraced steps before the trace")
    ap.add_argument("--trace-steps", type=int, default=12, help="traced control steps")
    ap.add_argument("--trace-stride", type=int, default=9, help="trace every n-th step")
    ap.add_argument("--batch", type=int, default=64)
    ap.add_argument("--block", type=int, default=100, help="control steps per timed block")
    ap.add_argument("--rounds", type=int, default=11, help="timed blocks")
    ap.add_argument("--trace-child", action="store_true", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.trace_child:
        trace_child(args.warm, args.trace_steps, args.trace_stride)
        return
    print(
        f"os.cpu_count() = {os.cpu_count()}; load average {os.getloadavg()[0]:.2f}; "
        f"numba {numba.__version__}; {time.strftime('%Y-%m-%d %H:%M')}"
    )
    part = args.part
    src = trace = tm = pk = None
    steps = traced_steps(args.warm, args.trace_steps, args.trace_stride)
    if part in ("all", "count", "trace"):
        n = args.steps if part == "count" else max(args.steps, steps[-1] + 1)
        per_step, differ = source_count(n)
        print(
            f"source replay of {n} control steps of one vehicle from reset against the "
            f"compiled kernel: {n - differ} steps bit-identical, {differ} differ"
        )
        src = report_count(per_step[: args.steps]) if part != "trace" else {}
        src["per_step_ops"] = [dict(by_op(c)) for c in per_step]
    if part in ("all", "trace"):
        results = machine_count(args.warm, args.trace_steps, args.trace_stride)
        trace = report_trace(results, steps, src)
    if part in ("all", "time"):
        tm = kernel_time(args.batch, args.block, args.rounds)
    if part in ("all", "peak"):
        pk = peak()
    if part == "all":
        summary(src, trace, tm, pk)
    print(f"load average at the end {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
