"""The Python API: thin calls into libcurvflow through ctypes (no second
implementation of any algorithm).

Arrays: V is (n, 3) float64 and F is (m, 3) int32, C-contiguous; such arrays
are handed to the library without a copy. Other real dtypes (float32, int64
faces from trimesh ...) and Fortran-ordered arrays (Eigen/libigl output) are
converted with a copy; complex, bool, object or string arrays, wrong shapes
and non-contiguous views (e.g. V[::2]) are refused with an exception that
names the problem. Everything the library validates (face indices out of
range, NaN coordinates, non-manifold edges ...) raises with the library's
message.
"""
import contextlib
import ctypes
import json
import logging
import math
import os
import signal
import threading
from ctypes import byref, c_double, c_int, c_int32, c_void_p, POINTER

import numpy as np

from . import _lib
from .errors import InvalidMeshError, UsageError, error_class, status_name

__all__ = ["flow", "edit", "spin", "compare", "load", "save", "info", "methods", "method_params",
           "write_log", "read_log"]

_logger = logging.getLogger("curvflow")
_INT32_MAX = 2**31 - 1


# ---- contexts and errors -------------------------------------------------------

def _log_line(user, level, line):
    # Library log lines (e.g. "polygons were fan-triangulated") go to the
    # "curvflow" logger; warnings therefore show on stderr by default, as
    # the CLI prints them. Must never raise into C.
    # Error-level lines are skipped: the same text becomes the exception.
    try:
        if level >= 3:
            return
        text = line.decode("utf-8", "replace")
        _logger.log({0: logging.DEBUG, 1: logging.INFO}.get(level, logging.WARNING), text)
    except BaseException:  # noqa: BLE001 - nothing may propagate into the library
        pass


_LOG_CALLBACK = _lib.LOG_FN(_log_line)


def solver_threads():
    """The solver threads that CURVFLOW_THREADS asks for: 1 (serial, the
    default) when it is unset, 0 (OpenMP and OpenBLAS as the process set
    them) or n > 1 (parallel); see cf_context_set_threads in curvflow.h.
    Raises UsageError for anything but an integer from 0 to 1024."""
    text = os.environ.get("CURVFLOW_THREADS")
    if text is None:
        return 1
    value = int(text) if 0 < len(text) <= 5 and all(c in "0123456789" for c in text) else None
    if value is None or value > 1024:
        raise UsageError("CURVFLOW_THREADS must be an integer from 0 to 1024, got %r" % text)
    return value


class _Context:
    """A cf_context for one call; every object made with it is destroyed
    before it (in reverse order of creation)."""

    def __init__(self):
        self.L = _lib.lib()
        self.ptr = c_void_p()
        st = self.L.cf_context_create(byref(self.ptr))
        if st != 0:
            raise error_class(st)("cannot create a curvflow context", status_name(st), st)
        self.L.cf_context_set_log(self.ptr, _LOG_CALLBACK, None, 2)  # warnings and errors
        self._cleanup = []
        # the solver threads, as the CLI takes them (cf_context_set_threads;
        # the library's default, 1, when CURVFLOW_THREADS is unset)
        threads = solver_threads()
        if threads != 1:
            self.L.cf_context_set_threads(self.ptr, threads)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
        return False

    def close(self):
        while self._cleanup:
            fn, arg = self._cleanup.pop()
            fn(byref(arg))
        if self.ptr:
            self.L.cf_context_destroy(byref(self.ptr))

    def defer(self, destroy, pointer):
        self._cleanup.append((destroy, pointer))

    def message(self):
        m = self.L.cf_context_message(self.ptr)
        return m.decode("utf-8", "replace") if m else ""

    def error(self, status, prefix=None, **extra):
        """The exception for a failed call, with the context's message."""
        msg = self.message() or self.L.cf_status_name(status).decode()
        if prefix and not msg.startswith(prefix + ":"):
            msg = "%s: %s" % (prefix, msg)
        return error_class(status)(msg, self.L.cf_status_name(status).decode(), status, **extra)

    def check(self, status, prefix=None):
        if status != 0:
            raise self.error(status, prefix)

    def mesh(self, V, F, uv=None, uv_faces=None, prefix=None):
        """A validated cf_mesh (the library copies the arrays)."""
        desc = _desc(V, F, uv, uv_faces)
        m = c_void_p()
        self.check(self.L.cf_mesh_create(self.ptr, byref(desc), byref(m)), prefix)
        self.defer(self.L.cf_mesh_destroy, m)
        return m


def _desc(V, F, uv=None, uv_faces=None):
    d = _lib.MeshDesc()
    d.vertex_count, d.positions = V.shape[0], V.ctypes.data
    d.face_count, d.triangles = F.shape[0], F.ctypes.data
    if uv is not None:
        d.uv_count, d.uv = uv.shape[0], uv.ctypes.data
        d.uv_triangles = uv_faces.ctypes.data if uv_faces is not None else None
    return d


# ---- array checks ---------------------------------------------------------------

def _array(a, name, columns, kinds, target, what):
    """Common checks: dtype kind, shape (n, columns) (or (n,) when columns is
    None), contiguity; returns a C-contiguous array of `target` dtype (the
    input itself when it already is one)."""
    if a is None:
        raise UsageError("%s is None, expected %s" % (name, what))
    arr = np.asarray(a)
    if arr.dtype.kind not in kinds:
        hint = " (convert with .astype(np.int32))" if target == np.int32 and arr.dtype.kind == "f" else ""
        raise TypeError("%s: expected %s, got dtype %s%s" % (name, what, arr.dtype, hint))
    shape = "(n, %d)" % columns if columns else "(n,)"
    if (columns and (arr.ndim != 2 or arr.shape[1] != columns)) or (not columns and arr.ndim != 1):
        raise UsageError("%s: expected shape %s, got %s" % (name, shape, arr.shape))
    if not (arr.flags.c_contiguous or arr.flags.f_contiguous):
        raise UsageError("%s is a non-contiguous view (shape %s, strides %s); pass np.ascontiguousarray(%s) "
                         "to copy it" % (name, arr.shape, arr.strides, name))
    if arr.shape[0] > _INT32_MAX:
        raise UsageError("%s: %d rows, more than the library's int32 limit" % (name, arr.shape[0]))
    if arr.dtype == target and arr.flags.c_contiguous and arr.dtype.isnative:
        return arr
    if target == np.int32 and arr.size:
        lo, hi = int(arr.min()), int(arr.max())
        if lo < -2**31 or hi > _INT32_MAX:
            bad = lo if lo < -2**31 else hi
            row = int(np.argwhere(arr == bad)[0][0])
            raise InvalidMeshError("%s: row %d: index %d does not fit the library's int32 indices" % (name, row, bad),
                                   "CF_ERR_INDEX_RANGE", -11)
    return np.ascontiguousarray(arr, dtype=target)


def _vertices(V, name="V"):
    return _array(V, name, 3, "fiu", np.float64, "real coordinates (float64)")


def _faces(F, name="F"):
    return _array(F, name, 3, "iu", np.int32, "integer vertex indices (int32)")


def _same_count(V, other, name):
    if other.shape[0] != V.shape[0]:
        raise UsageError("%s has %d rows, V has %d vertices" % (name, other.shape[0], V.shape[0]))


def _copy_out(ptr, shape):
    n = int(np.prod(shape))
    return np.ctypeslib.as_array(ptr, shape=(n,)).reshape(shape).copy()


# ---- methods and parameters -----------------------------------------------------

def methods():
    """Names of the flow methods (as `curvflow flow --list-methods`), with
    their descriptions: {name: description}."""
    L = _lib.lib()
    out = {}
    k = 0
    while True:
        name = L.cf_flow_kind_name(k)
        if not name:
            return out
        out[name.decode()] = L.cf_flow_kind_description(k).decode()
        k += 1


def _kind(method):
    L = _lib.lib()
    if not isinstance(method, str):
        raise TypeError("method: expected a method name (str), got %r" % (method,))
    k = c_int()
    if L.cf_flow_kind_from_name(method.encode(), byref(k)) != 0:
        raise UsageError("unknown method '%s' (methods: %s)" % (method, ", ".join(methods())),
                         "CF_ERR_INVALID_ARG", -1)
    return k.value


_TYPES = {0: "double", 1: "int", 2: "bool", 3: "choice", 4: "vertex-scalars", 5: "vertex-vectors",
          6: "face-scalars", 7: "point-set"}


def method_params(method):
    """Parameters of a method with their defaults, ranges and help (as
    `curvflow flow --method NAME --list-params`): {name: dict}, the method's
    own first, then the step policy common to every method (energy_check,
    backtrack, max_halvings, halving_search, step_growth, rise_tolerance,
    divergence_tolerance, energy_floor, blowup_factor, divergence_factor,
    whose defaults depend on the method; docs/flowcli.md). Each dict: type,
    default (text, as the CLI prints it), help, group ("method" or
    "step-policy"), accepts (the accepted values as the CLI prints them,
    e.g. "[0, 60]" or "true|false"), and range (min, max) for numbers or
    choices for choices. All of them are set by name in curvflow.flow."""
    L = _lib.lib()
    kind = _kind(method)
    opts = _lib.FlowOptions()
    L.cf_flow_options_default(kind, byref(opts))
    out = {}
    buf = ctypes.create_string_buffer(128)
    accepts = ctypes.create_string_buffer(256)
    for group in ("method", "step-policy"):
        table = POINTER(_lib.ParamDesc)()
        count = c_int32()
        if group == "method":
            L.cf_flow_params(kind, byref(table), byref(count))
        else:
            L.cf_flow_common_params(byref(table), byref(count))
        for i in range(count.value):
            p = table[i]
            L.cf_flow_options_format(byref(opts), ctypes.byref(p), buf, len(buf))
            L.cf_flow_param_range_format(ctypes.byref(p), accepts, len(accepts))
            entry = {"type": _TYPES.get(p.type, "?"), "default": buf.value.decode(),
                     "help": p.help.decode() if p.help else "", "group": group,
                     "accepts": accepts.value.decode()}
            if p.type in (0, 1):
                entry["range"] = (p.min_value, p.max_value)
            if p.type == 3:
                choices, j = [], 0
                while p.choices[j]:
                    choices.append(p.choices[j].decode())
                    j += 1
                entry["choices"] = choices
            out[p.name.decode()] = entry
    return out


def _param_text(name, value):
    """Text form accepted by cf_flow_options_set (floats with repr: 17
    significant digits at most, read back exactly by strtod)."""
    if isinstance(value, (bool, np.bool_)):
        return "true" if value else "false"
    if isinstance(value, (int, np.integer)):
        return str(int(value))
    if isinstance(value, (float, np.floating)):
        return repr(float(value))
    if isinstance(value, str):
        return value
    raise TypeError("parameter %s: expected a number, bool or name, got %s" % (name, type(value).__name__))


def _set(ctx, opts, name, value):
    st = ctx.L.cf_flow_options_set(ctx.ptr, byref(opts), name.encode(), _param_text(name, value).encode())
    ctx.check(st)


def _method_struct(opts, method):
    mirror = _lib.check_options_layout(method)
    return mirror.from_buffer(opts.storage)


def _handle_set(ctx, mesh, start, handles):
    """A cf_handle_set from a JSON file path, a JSON document (dict/list, see
    docs/edit.md) or a (vertices, targets) pair of arrays."""
    L = ctx.L
    out = POINTER(_lib.HandleSet)()
    start_ptr = start.ctypes.data if start is not None else None
    if isinstance(handles, (str, os.PathLike)):
        path = os.fspath(handles)
        st = L.cf_handle_set_read_json(ctx.ptr, mesh, start_ptr, path.encode(), byref(out))
    elif isinstance(handles, dict):
        text = json.dumps(handles, default=lambda o: o.tolist() if hasattr(o, "tolist") else str(o))
        st = L.cf_handle_set_parse_json(ctx.ptr, mesh, start_ptr, text.encode(), b"handles", byref(out))
    elif isinstance(handles, (tuple, list)) and len(handles) == 2:
        verts = _array(handles[0], "handles[0] (vertices)", None, "iu", np.int32, "vertex indices")
        targets = _vertices(handles[1], "handles[1] (targets)")
        if targets.shape[0] != verts.shape[0]:
            raise UsageError("handles: %d vertices but %d targets" % (verts.shape[0], targets.shape[0]))
        st = L.cf_handle_set_create(ctx.ptr, verts.shape[0], verts.ctypes.data, targets.ctypes.data, byref(out))
    else:
        raise TypeError("handles: expected a JSON file path, a JSON document (dict) or a (vertices, targets) "
                        "pair, got %s" % type(handles).__name__)
    ctx.check(st, "handles" if not isinstance(handles, (str, os.PathLike)) else None)
    ctx.defer(L.cf_handle_set_destroy, out)
    return out


# ---- flows ---------------------------------------------------------------------

def _info_dict(info):
    """One log entry, in the CLI's --log JSONL layout (NaN/Inf as None)."""
    def num(v):
        return v if math.isfinite(v) else None
    terms = {info.term_names[i].decode(): num(info.energy_terms[i])
             for i in range(_lib.MAX_TERMS) if info.term_names[i]}
    res = {info.residual_names[i].decode(): num(info.residuals[i])
           for i in range(_lib.MAX_RESIDUALS) if info.residual_names[i]}
    return {"iteration": info.iteration, "time": num(info.time), "time_step": num(info.time_step),
            "energy": num(info.energy), "terms": terms, "residuals": res, "area": num(info.area),
            "volume": num(info.volume), "area_drift": num(info.area_drift), "volume_drift": num(info.volume_drift),
            "seconds": {"assemble": num(info.assemble_seconds), "factorize": num(info.factorize_seconds),
                        "solve": num(info.solve_seconds), "total": num(info.total_seconds)}}


@contextlib.contextmanager
def _sigint_requests():
    """While a flow runs in the main thread with Python's default SIGINT
    handler, Ctrl-C only records the request; the progress callback then
    cancels the flow through the library's hook at the end of the current
    step. (Raising KeyboardInterrupt from the handler itself could land
    outside the callback's guard and be lost inside ctypes.)"""
    state = {"sigint": False}
    if (threading.current_thread() is threading.main_thread()
            and signal.getsignal(signal.SIGINT) is signal.default_int_handler):
        def handler(signum, frame):
            state["sigint"] = True
        previous = signal.signal(signal.SIGINT, handler)
        try:
            yield state
        finally:
            signal.signal(signal.SIGINT, previous)
    else:
        yield state


def _options(ctx, method, kind, time_step, params, handles=None):
    """cf_flow_options of `method` with time_step and the scalar parameters
    set by name (cf_flow_options_set, in the CLI's order: boundary targets
    imply boundary=prescribed first, then time_step, then the others).
    Returns (options, boundary_targets, rest_positions); the array-valued
    ones are attached once the mesh exists."""
    opts = _lib.FlowOptions()
    ctx.L.cf_flow_options_default(kind, byref(opts))
    params = dict(params)
    targets = params.pop("boundary_targets", None)
    axis = params.pop("boundary_axis", None)
    rest = params.pop("rest_positions", None)
    if method != "spin-willmore" and (targets is not None or axis is not None):
        raise UsageError("boundary_targets / boundary_axis are parameters of spin-willmore")
    if method != "stretch-bend-edit" and (rest is not None or handles is not None):
        raise UsageError("handles / rest_positions are parameters of stretch-bend-edit (curvflow.edit)")
    if targets is not None:
        # as the CLI's --boundary-targets: implies boundary=prescribed
        # (set first, so a contradicting `boundary` is refused when attached)
        _set(ctx, opts, "boundary", "prescribed")
    if time_step is not None:
        _set(ctx, opts, "time_step", time_step)
    if axis is not None:
        a = np.asarray(axis, dtype=np.float64).reshape(-1)
        if a.shape != (3,):
            raise UsageError("boundary_axis: expected 3 numbers, got shape %s" % (np.shape(axis),))
        for c, v in zip("xyz", a):
            _set(ctx, opts, "boundary_axis_" + c, float(v))
    for name, value in params.items():
        if isinstance(value, (np.ndarray, list, tuple)):
            raise UsageError("parameter %s of %s takes a single value, got an array" % (name, method))
        _set(ctx, opts, name, value)
    return opts, targets, rest


def check_params(method, time_step=None, **params):
    """Checks a method name and its parameters as curvflow.flow would set
    them (without a mesh): raises UsageError naming the problem. Array-valued
    parameters are only checked by name."""
    kind = _kind(method)
    with _Context() as ctx:
        _options(ctx, method, kind, time_step, params, params.pop("handles", None))


def _run(method, V, F, steps, time_step, callback, params, start=None, handles=None):
    kind = _kind(method)
    V = _vertices(V)
    F = _faces(F)
    if isinstance(steps, bool) or not isinstance(steps, (int, np.integer)) or steps < 0:
        raise UsageError("steps: expected an integer >= 0, got %r" % (steps,))
    if callback is not None and not callable(callback):
        raise TypeError("callback: expected a callable, got %s" % type(callback).__name__)
    with _Context() as ctx:
        L = ctx.L
        keep = []  # arrays the options point to, alive until the flow is destroyed
        opts, targets, rest = _options(ctx, method, kind, time_step, params, handles)
        if start is not None:
            start = _vertices(start, "start")
            _same_count(V, start, "start")
        mesh = ctx.mesh(V, F)
        if targets is not None:
            m = _method_struct(opts, method)
            if m.boundary_mode != 2:
                raise UsageError("boundary_targets needs boundary=prescribed")
            t = _vertices(targets, "boundary_targets")
            _same_count(V, t, "boundary_targets")
            keep.append(t)
            m.boundary_targets.values = t.ctypes.data
            m.boundary_targets.count = t.shape[0]
        if method == "stretch-bend-edit":
            if handles is None:
                raise UsageError("stretch-bend-edit needs handles=... (a JSON file, a JSON document or "
                                 "(vertices, targets)); see curvflow.edit")
            m = _method_struct(opts, method)
            hs = _handle_set(ctx, mesh, start, handles)
            m.handles = ctypes.cast(hs, c_void_p)
            if rest is not None:
                r = _vertices(rest, "rest_positions")
                _same_count(V, r, "rest_positions")
                keep.append(r)
                m.rest_positions = r.ctypes.data
        fl = c_void_p()
        # the mesh is the reference, start only the initial state (as the CLI's --start)
        st = L.cf_flow_create_at(ctx.ptr, mesh, start.ctypes.data if start is not None else None, byref(opts),
                              byref(fl))
        ctx.check(st)
        ctx.defer(L.cf_flow_destroy, fl)
        n = V.shape[0]
        log = [_info_dict(L.cf_flow_last_info(fl).contents)]
        raised = []
        stop = {"user": False}

        with _sigint_requests() as sig:
            def progress(user, info_ptr):
                try:
                    entry = _info_dict(info_ptr.contents)
                    log.append(entry)
                    if callback is not None and callback(entry):
                        stop["user"] = True
                        return 1
                    return 1 if sig["sigint"] else 0
                except BaseException as e:  # noqa: BLE001 - re-raised after the run
                    raised.append(e)
                    return 1

            fn = _lib.PROGRESS_FN(progress)
            L.cf_flow_set_progress(fl, fn, None)
            info = _lib.FlowInfo()
            st = L.cf_flow_run(fl, int(steps), byref(info))
            L.cf_flow_set_progress(fl, _lib.PROGRESS_FN(), None)
        positions = _copy_out(L.cf_flow_positions(fl), (n, 3))
        if raised:
            e = raised[0]
            if isinstance(e, KeyboardInterrupt):
                e = _interrupted(log)
            e.last_positions, e.log = positions, log
            raise e
        if sig["sigint"]:
            e = _interrupted(log)
            e.last_positions, e.log = positions, log
            raise e
        if st == -8 and stop["user"]:
            return positions, log
        if st != 0:
            raise ctx.error(st, last_positions=positions, log=log)
        return positions, log


def _interrupted(log):
    return KeyboardInterrupt("curvflow: flow cancelled after iteration %d (Ctrl-C); the state reached is in "
                             ".last_positions" % log[-1]["iteration"])


def flow(V, F, method, steps=10, time_step=None, callback=None, **params):
    """Runs a flow method of the library (`curvflow flow --method NAME`).

    V: (n, 3) float64 positions; F: (m, 3) int32 counter-clockwise
    triangles. method: one of curvflow.methods(). steps: at most this many
    steps (the flow may stop earlier when the method reports convergence).
    time_step: the method's scale-free time step (None: its default).
    callback(entry): called after each step with that step's log entry;
    returning True stops the flow there (a normal return). Exceptions it
    raises cancel the flow and are re-raised; Ctrl-C cancels at the end of
    the current step and raises KeyboardInterrupt (with .last_positions).
    params: method parameters by name (curvflow.method_params(method)),
    e.g. sigma=0.5, boundary="fixed"; array-valued: boundary_targets (n, 3)
    and boundary_axis (3,) for spin-willmore, handles and rest_positions
    for stretch-bend-edit (see curvflow.edit).

    Returns (V_out, log): the final (n, 3) positions and one dict per step
    (entry 0 is the start), in the layout of the CLI's --log JSONL.
    Raises UsageError (unknown method/parameter, bad value), InvalidMeshError,
    NumericalError (with .last_positions and .log: the last good state), ...
    """
    params = dict(params)
    handles = params.pop("handles", None)
    return _run(method, V, F, steps, time_step, callback, params, handles=handles)


def edit(V, F, handles, energy="hybrid", iterations=100, tol=1e-6, start=None, callback=None, **params):
    """Mesh editing with the stretching + bending energy of Zhao & Gortler
    or ARAP (`curvflow edit`): moves the handle vertices to their targets
    and minimises the energy by local/global iteration from the rest pose V
    (or from `start`, (n, 3)).

    handles: a JSON handle file path, the same JSON as a dict (format in
    docs/edit.md), or a pair (vertices (k,), targets (k, 3)).
    energy: hybrid, stretch, bend, arap, arap-rims. iterations, tol: as the
    CLI's --iterations and --tol. params: lambda_ (or "lambda" via **),
    mass, scale_free, anderson, arap_weights ("cotan" or "clamped", as the
    CLI's --arap-weights). Returns (V_out, log) as curvflow.flow.
    """
    params = dict(params)
    if "lambda_" in params:
        params["lambda"] = params.pop("lambda_")
    if isinstance(iterations, bool) or not isinstance(iterations, (int, np.integer)) or iterations < 0:
        raise UsageError("iterations: expected an integer >= 0, got %r" % (iterations,))
    ordered = {"energy": energy}
    if "lambda" in params:
        ordered["lambda"] = params.pop("lambda")
    ordered["max_iterations"] = max(int(iterations), 1)  # the flow runs `iterations` steps itself
    ordered["relative_tolerance"] = tol
    ordered.update(params)
    return _run("stretch-bend-edit", V, F, iterations, None, callback, ordered, start=start, handles=handles)


def spin(V, F, rho):
    """Spin transformation (`curvflow spin`): the conformal deformation of
    (V, F) whose mean curvature is H + rho to first order. rho: (n,) change
    of mean curvature per vertex (1/length). Returns the (n, 3) positions."""
    V = _vertices(V)
    F = _faces(F)
    r = _array(rho, "rho", None, "fiu", np.float64, "real values (float64)")
    _same_count(V, r, "rho")
    with _Context() as ctx:
        mesh = ctx.mesh(V, F)
        out = np.empty_like(V)
        ctx.check(ctx.L.cf_spin_transform(ctx.ptr, mesh, None, r.ctypes.data, out.ctypes.data))
        return out


def _stats(s):
    return {"mean": s.weighted_mean, "std": s.weighted_std, "min": s.min, "median": s.p50, "p95": s.p95,
            "max": s.max}


def compare(V0, V1, F):
    """Compares two position sets on one connectivity (`curvflow compare`):
    per-face quasi-conformal error Q (1 = conformal) and log area distortion,
    per-vertex largest angle change (radians). Statistics are area-weighted
    with the areas of V0 (keys mean, std, min, median, p95, max as in
    `compare --json`); "Q" and "log_area_distortion" are the per-face arrays
    (m,), "angle_change_per_vertex" the per-vertex array (n,).
    "vertex_scale_model_q" (with "invalid_faces" and "rms_log_length_residual")
    is the vertex-scale model of `compare`: log scales fitted at the vertices to
    the change of edge lengths ("log_scale", (n,)) and the Q of each face with its
    lengths so rescaled ("vertex_scale_model_q_per_face", (m,), NaN where they form
    no triangle): the Q that the conformal scale's variation causes by itself.
    "conformal_class": on a closed connected surface of genus >= 1 the distance
    between the conformal classes of V0 and V1 ("genus", "distance"; for genus 1
    also the moduli "modulus_a", "modulus_b" as (real, imag) in the standard
    fundamental domain), as `compare --json`; None on other surfaces."""
    V0 = _vertices(V0, "V0")
    V1 = _vertices(V1, "V1")
    F = _faces(F)
    _same_count(V0, V1, "V1")
    with _Context() as ctx:
        mesh = ctx.mesh(V0, F)
        m, n = F.shape[0], V0.shape[0]
        q, lad, ang = np.empty(m), np.empty(m), np.empty(n)
        sq, sl, sa = _lib.Stats(), _lib.Stats(), _lib.Stats()
        a, b = V0.ctypes.data, V1.ctypes.data
        ctx.check(ctx.L.cf_quasi_conformal_error(ctx.ptr, mesh, a, b, q.ctypes.data, byref(sq)))
        ctx.check(ctx.L.cf_log_area_distortion(ctx.ptr, mesh, a, b, lad.ctypes.data, byref(sl)))
        ctx.check(ctx.L.cf_angle_change(ctx.ptr, mesh, a, b, ang.ctypes.data, byref(sa)))
        u, qm, fit = np.empty(n), np.empty(m), _lib.VertexScaleFit()
        ctx.check(ctx.L.cf_vertex_scale_fit_compute(ctx.ptr, mesh, a, b, u.ctypes.data, qm.ctypes.data, byref(fit)))
        model = dict(_stats(fit.q), invalid_faces=fit.invalid_faces, rms_log_length_residual=fit.rms_residual)
        cls = None
        L = ctx.L
        if L.cf_mesh_component_count(mesh) == 1 and L.cf_mesh_boundary_loop_count(mesh) == 0 and L.cf_mesh_genus(mesh) >= 1:
            ca, cb, dist = _lib.ConformalClass(), _lib.ConformalClass(), c_double()
            # as `compare`: a class that cannot be measured (a degenerate face of V1) is said, not raised
            if L.cf_conformal_class_distance(ctx.ptr, mesh, a, b, byref(ca), byref(cb), byref(dist)) == 0:
                cls = {"genus": ca.genus, "distance": dist.value}
                if ca.genus == 1:
                    cls.update(modulus_a=tuple(ca.modulus), modulus_b=tuple(cb.modulus))
            else:
                cls = {"error": ctx.message()}
        return {"conformal_class": cls, "faces": m, "quasi_conformal_error": _stats(sq), "log_area_distortion": _stats(sl),
                "angle_change": dict(_stats(sa), unit="radians"), "vertex_scale_model_q": model, "Q": q,
                "log_area_distortion_per_face": lad, "angle_change_per_vertex": ang, "log_scale": u,
                "vertex_scale_model_q_per_face": qm}


# ---- files -----------------------------------------------------------------------

def _read(ctx, path):
    data = POINTER(_lib.MeshData)()
    st = ctx.L.cf_read_mesh_file(ctx.ptr, os.fsencode(path), byref(data))
    ctx.check(st, os.fspath(path))
    ctx.defer(ctx.L.cf_mesh_data_destroy, data)
    return data.contents


def _read_welded(ctx, path):
    """The file's data without the vertices no face uses
    (cf_mesh_data_drop_unreferenced, docs/io.md "Unused vertices") and with its
    seams welded (cf_mesh_data_weld, "Seams"), as the commands read it: the
    data, the weld's report and the number of unused vertices dropped."""
    d = _read(ctx, path)
    dropped = c_int32(0)
    ctx.check(ctx.L.cf_mesh_data_drop_unreferenced(ctx.ptr, byref(d), None, byref(dropped)), os.fspath(path))
    report = _lib.WeldReport()
    ctx.check(ctx.L.cf_mesh_data_weld(ctx.ptr, byref(d), None, byref(report)), os.fspath(path))
    return d, report, dropped.value


def _weld_dict(report):
    return {"coincident_boundary_vertices": report.candidates, "positions": report.groups,
            "welded": bool(report.welded), "removed": report.removed, "vertices": report.vertices,
            "differing_properties": report.differing_properties,
            "refused": report.refused.decode("utf-8", "replace") or None}


def _names(d):
    """What a file carries besides the mesh, by name (no values copied): its
    vertex and face property names and its OBJ material libraries and names."""
    libs = ctypes.cast(d.material_libraries, POINTER(ctypes.c_char_p))
    names = ctypes.cast(d.material_names, POINTER(ctypes.c_char_p))
    return {"vertex_properties": [d.vertex_properties[i].name.decode() for i in range(d.vertex_property_count)],
            "face_properties": [d.face_properties[i].name.decode() for i in range(d.face_property_count)],
            "material_libraries": [os.fsdecode(libs[i]) for i in range(d.material_library_count)],
            "material_names": [os.fsdecode(names[i]) for i in range(d.material_count)]}


def _extras(d):
    uv = uv_faces = None
    if d.uv_count:
        uv = _copy_out(d.uv, (d.uv_count, 2))
        if d.uv_triangles:
            uv_faces = _copy_out(d.uv_triangles, (d.face_count, 3))
    named = _names(d)
    vf = {name: _copy_out(d.vertex_properties[i].values, (d.vertex_count,))
          for i, name in enumerate(named["vertex_properties"])}
    ff = {name: _copy_out(d.face_properties[i].values, (d.face_count,))
          for i, name in enumerate(named["face_properties"])}
    return {"uv": uv, "uv_faces": uv_faces, "vertex_fields": vf, "face_fields": ff,
            "polygons_triangulated": d.polygon_count,
            "material_libraries": named["material_libraries"], "material_names": named["material_names"],
            "face_materials": (_copy_out(ctypes.cast(d.face_materials, POINTER(c_int32)), (d.face_count,))
                               if d.face_materials else None)}


def load(path, validate=True, weld=True):
    """Reads an OBJ, OFF or PLY file (format from the extension).

    Returns (V, F, extras): V (n, 3) float64, F (m, 3) int32 (polygons
    fan-triangulated), extras a dict with "uv" ((k, 2) texture coordinates
    or None), "uv_faces" ((m, 3) indices into uv for per-corner coordinates,
    None when they are per vertex or absent), "vertex_fields" / "face_fields"
    ({name: array} from PLY properties, and the colours of an OBJ or OFF as
    red / green / blue [/ alpha] in 0..255), "polygons_triangulated" and an OBJ's
    materials: "material_libraries" (the text after each `mtllib`, as written),
    "material_names" (in order of first `usemtl`) and "face_materials" ((m,)
    int32 indices into material_names, -1 before the first `usemtl`; None
    when the file has none). Pass the last three to save() to keep them.
    With validate=True (default) the mesh is checked as every command checks
    it (InvalidMeshError naming the file and element, e.g. a non-manifold
    edge); validate=False returns what the file holds (syntax, index range
    and finite coordinates are always checked). Unreadable files raise
    MeshIOError / MeshFormatError with the file and line.
    With weld=True (default, as the command-line tool) boundary vertices at
    exactly the position of another boundary vertex (texture or normal seams,
    unshared triangles) are joined when the result is a valid mesh, and the
    arrays are the welded mesh's (per-vertex uv become per-corner; docs/io.md,
    "Seams"); extras["weld"] says what was found and done (keys
    coincident_boundary_vertices, positions, welded, removed, vertices,
    differing_properties, refused: why a weld was left undone, or None).
    It also drops the vertices that no face uses, as the commands do (a mesh
    with one is refused; docs/io.md, "Unused vertices"):
    extras["unused_vertices_dropped"] is how many (None with weld=False).
    weld=False keeps the file's vertices."""
    with _Context() as ctx:
        d, report, dropped = _read_welded(ctx, path) if weld else (_read(ctx, path), None, None)
        if validate:
            desc = _lib.MeshDesc()
            ctx.L.cf_mesh_data_desc(byref(d), byref(desc))
            m = c_void_p()
            ctx.check(ctx.L.cf_mesh_create(ctx.ptr, byref(desc), byref(m)), os.fspath(path))
            ctx.defer(ctx.L.cf_mesh_destroy, m)
        V = _copy_out(d.positions, (d.vertex_count, 3))
        F = _copy_out(d.triangles, (d.face_count, 3))
        extras = _extras(d)
        extras["weld"] = _weld_dict(report) if report is not None else None
        extras["unused_vertices_dropped"] = dropped
        return V, F, extras


_PLY_ENCODINGS = {"binary": 0, "binary_little_endian": 0, "binary_big_endian": 1, "ascii": 2}


def save(path, V, F, fields=None, uv=None, uv_faces=None, vertex_fields=None, face_fields=None,
         ply_encoding="binary", material_libraries=None, material_names=None, face_materials=None):
    """Writes a mesh atomically (temporary file + rename: an existing file is
    replaced only by a complete one). Format from the extension.

    fields: {name: array} with one value per vertex (n,) or per face (m,)
    (the location follows from the length; use vertex_fields / face_fields
    when n == m). PLY stores them as double properties, OBJ in side files
    <stem>.vertex.csv / <stem>.face.csv (17 digits), OFF refuses them.
    uv: texture coordinates, (n, 2) per vertex or (k, 2) with uv_faces
    (m, 3) per corner. Positions are written exactly (binary PLY, or %.17g
    text). The mesh is validated first (InvalidMeshError).
    OBJ only: material_libraries (list of str, one `mtllib` line each),
    material_names (list of str) and face_materials ((m,) indices into
    material_names, -1 for none: a `usemtl` line starts each run of faces of
    one material), as load() returns them. Another format refuses them
    (UsageError): it has no place for them."""
    V = _vertices(V)
    F = _faces(F)
    if uv is not None:
        uv = _array(uv, "uv", 2, "fiu", np.float64, "real texture coordinates")
        if uv_faces is not None:
            uv_faces = _faces(uv_faces, "uv_faces")
            if uv_faces.shape[0] != F.shape[0]:
                raise UsageError("uv_faces has %d rows, F has %d faces" % (uv_faces.shape[0], F.shape[0]))
        elif uv.shape[0] != V.shape[0]:
            raise UsageError("uv has %d rows but V has %d vertices (pass uv_faces for per-corner uv)"
                             % (uv.shape[0], V.shape[0]))
    elif uv_faces is not None:
        raise UsageError("uv_faces given without uv")
    n, m = V.shape[0], F.shape[0]
    entries = []
    for name, values in (fields or {}).items():
        a = np.asarray(values)
        if a.ndim != 1 or a.shape[0] not in (n, m):
            raise UsageError("field %s: expected %d (vertices) or %d (faces) values, got shape %s"
                             % (name, n, m, a.shape))
        if n == m:
            raise UsageError("field %s: as many vertices as faces (%d); pass it in vertex_fields or "
                             "face_fields" % (name, n))
        entries.append((name, 0 if a.shape[0] == n else 1, a))
    for loc, group in ((0, vertex_fields), (1, face_fields)):
        for name, values in (group or {}).items():
            entries.append((name, loc, values))
    if ply_encoding not in _PLY_ENCODINGS:
        raise UsageError("ply_encoding: expected one of %s, got %r" % (", ".join(_PLY_ENCODINGS), ply_encoding))
    keep = []
    cfields = (_lib.Field * max(len(entries), 1))()
    for i, (name, loc, values) in enumerate(entries):
        if not isinstance(name, str):
            raise TypeError("field names must be str, got %r" % (name,))
        a = _array(values, "field %s" % name, None, "fiub", np.float64, "real values")
        expected = n if loc == 0 else m
        if a.shape[0] != expected:
            raise UsageError("field %s: expected %d %s values, got %d"
                             % (name, expected, "vertex" if loc == 0 else "face", a.shape[0]))
        keep.append((name.encode(), a))
        cfields[i].name, cfields[i].location, cfields[i].values = keep[-1][0], loc, a.ctypes.data
    materials = _materials(path, m, material_libraries, material_names, face_materials)
    with _Context() as ctx:
        mesh = ctx.mesh(V, F, uv, uv_faces)
        wo = _lib.WriteOptions()
        ctx.L.cf_write_options_default(byref(wo))
        wo.ply_encoding = _PLY_ENCODINGS[ply_encoding]
        if materials:
            (libs, nlibs), (names, nnames), fm = materials
            wo.material_library_count, wo.material_libraries = nlibs, ctypes.cast(libs, c_void_p)
            wo.material_count, wo.material_names = nnames, ctypes.cast(names, c_void_p)
            wo.face_materials = fm.ctypes.data if fm is not None else None
        st = ctx.L.cf_write_mesh_file_ex(ctx.ptr, os.fsencode(path), mesh, None, cfields, len(entries), byref(wo))
        ctx.check(st, os.fspath(path))


def _text_list(values, name):
    if not all(isinstance(v, str) for v in values):
        raise TypeError("%s: expected a list of str, got %r" % (name, values))
    out = (ctypes.c_char_p * max(len(values), 1))()
    for i, v in enumerate(values):
        out[i] = os.fsencode(v)  # the array keeps its own references to the bytes
    return out, len(values)


def _materials(path, face_count, libraries, names, face_materials):
    """save()'s material arguments as the C lists, or None when there are none."""
    for value, name in ((libraries, "material_libraries"), (names, "material_names")):
        if isinstance(value, (str, bytes)):
            raise TypeError("%s: expected a list of str, got %r" % (name, value))
    libraries, names = list(libraries or []), list(names or [])
    if not libraries and not names and face_materials is None:
        return None
    ext = os.path.splitext(os.fspath(path))[1].lower()
    if ext != ".obj":
        raise UsageError("%s: materials (mtllib / usemtl) can only be written to an OBJ file" % os.fspath(path))
    fm = None
    if face_materials is not None:
        if not names:
            raise UsageError("face_materials given without material_names")
        fm = _array(face_materials, "face_materials", None, "iu", np.int32, "integer material indices (int32)")
        if fm.shape[0] != face_count:
            raise UsageError("face_materials has %d entries, F has %d faces" % (fm.shape[0], face_count))
        bad = np.flatnonzero((fm < -1) | (fm >= len(names)))
        if bad.size:
            raise UsageError("face_materials: face %d has material %d, expected -1 .. %d"
                             % (bad[0], fm[bad[0]], len(names) - 1))
    return _text_list(libraries, "material_libraries"), _text_list(names, "material_names"), fm


def write_text_atomic(path, text):
    """Writes text to path atomically with the library's writer (temporary
    file in the same directory, fsync, rename)."""
    data = text.encode("utf-8")
    with _Context() as ctx:
        ctx.check(ctx.L.cf_write_text_file_atomic(ctx.ptr, os.fsencode(path), data, len(data)))


def write_log(path, log):
    """Writes a flow log (list of dicts from curvflow.flow) as JSONL, one
    object per step in the CLI's --log layout, atomically."""
    lines = [json.dumps(entry, allow_nan=False, separators=(",", ":")) for entry in log]
    write_text_atomic(path, "".join(line + "\n" for line in lines))


def read_log(path):
    """Reads a JSONL flow log (the CLI's --log or write_log's) into a list of dicts."""
    with open(path, encoding="utf-8") as fp:
        return [json.loads(line) for line in fp if line.strip()]


# ---- info ------------------------------------------------------------------------

def weld(V, F):
    """Joins the seams of arrays as load() does those of a file (docs/io.md,
    "Seams"): every boundary vertex at exactly the position of another
    boundary vertex is replaced by the one of lowest index, if the result is
    a valid mesh. Returns (V, F, index, report): the welded arrays, index
    (n,) int32 the new index of every input vertex (per-vertex data d of the
    input becomes d[kept] with kept = the first vertex of each new index, and
    per-corner data keeps its corners), and report the dict of
    load()'s extras["weld"]. Nothing to weld, or a weld refused (report
    "refused"), returns copies of V and F with the identity index."""
    V = _vertices(V)
    F = _faces(F)
    index = np.empty(V.shape[0], dtype=np.int32)
    report = _lib.WeldReport()
    with _Context() as ctx:
        ctx.check(ctx.L.cf_weld_map(ctx.ptr, V.shape[0], V.ctypes.data, F.shape[0], F.ctypes.data,
                                    index.ctypes.data, byref(report)), "weld")
    # kept vertices take the next index in order; a joined one an earlier one
    before = np.concatenate([[-1], np.maximum.accumulate(index)[:-1]]) if len(index) else index
    kept = index == before + 1
    return V[kept].copy(), index[F], index, _weld_dict(report)


def loop_subdivide(V, F, levels=1):
    """Loop subdivision (Loop 1987; boundary rules of Hoppe et al. 1994),
    `levels` times (1 to 10; each multiplies the face count by 4): returns
    (V, F) of the finer mesh, whose first len(V) vertices are the input's,
    moved by the Loop rules. The input must be a valid mesh
    (InvalidMeshError otherwise)."""
    V = _vertices(V)
    F = _faces(F)
    if isinstance(levels, bool) or not isinstance(levels, (int, np.integer)):
        raise TypeError("levels: expected an integer, got %r" % (levels,))
    with _Context() as ctx:
        mesh = ctx.mesh(V, F)
        out = c_void_p()
        ctx.check(ctx.L.cf_loop_subdivide(ctx.ptr, mesh, V.ctypes.data, int(levels), byref(out)), "loop_subdivide")
        ctx.defer(ctx.L.cf_mesh_destroy, out)
        nv, nf = ctx.L.cf_mesh_vertex_count(out), ctx.L.cf_mesh_face_count(out)
        return _copy_out(ctx.L.cf_mesh_positions(out), (nv, 3)), _copy_out(ctx.L.cf_mesh_triangles(out), (nf, 3))


def _seams(ctx, path):
    """What load() and the commands weld in the file, as `curvflow info --json`
    reports it ("seams")."""
    d, report, dropped = _read_welded(ctx, path)
    out = {"unused_vertices": dropped, "coincident_boundary_vertices": report.candidates, "positions": report.groups,
           "welded_vertices": None, "welded_boundary_loops": None, "welded_genus": None,
           "refused": report.refused.decode("utf-8", "replace") or None}
    if report.welded:
        desc = _lib.MeshDesc()
        ctx.L.cf_mesh_data_desc(byref(d), byref(desc))
        m = c_void_p()
        ctx.check(ctx.L.cf_mesh_create(ctx.ptr, byref(desc), byref(m)), os.fspath(path))
        ctx.defer(ctx.L.cf_mesh_destroy, m)
        out.update(welded_vertices=report.vertices, welded_boundary_loops=ctx.L.cf_mesh_boundary_loop_count(m),
                   welded_genus=ctx.L.cf_mesh_genus(m))
    return out


def info(V_or_path, F=None):
    """Mesh summary as `curvflow info --json`: counts, texture coordinates,
    (for a file) the names of its vertex and face properties and its OBJ
    material libraries and names, the validation report (every defect counted), and for a valid mesh
    edges, components, boundary loops, Euler characteristic, genus, corner
    angle and face area statistics, W/4pi and volume (closed meshes); for a
    file also "seams": its boundary vertices that lie on others and what
    load() and the commands weld of them (docs/io.md, "Seams").
    Accepts a file path (the file may hold an invalid mesh: the report says
    why) or arrays V, F. Never raises for an invalid mesh; raises for an
    unreadable file."""
    with _Context() as ctx:
        L = ctx.L
        out = {}
        if F is None:
            path = os.fspath(V_or_path)
            d = _read(ctx, path)
            desc = _lib.MeshDesc()
            L.cf_mesh_data_desc(byref(d), byref(desc))
            out["file"] = path
            out["vertices"], out["faces"] = d.vertex_count, d.face_count
            out["polygons_triangulated"] = d.polygon_count
            out["texture_coordinates"] = ("none" if d.uv_count == 0 else
                                          "per-corner" if d.uv_triangles else "per-vertex")
            out.update(_names(d))  # names only: no property values copied
            out["seams"] = _seams(ctx, path)
        else:
            V, Fa = _vertices(V_or_path), _faces(F)
            desc = _desc(V, Fa)
            out["vertices"], out["faces"] = V.shape[0], Fa.shape[0]
        report = _lib.MeshReport()
        ctx.check(L.cf_mesh_validate(ctx.ptr, byref(desc), byref(report)))
        valid = report.first_status == 0
        val = {"valid": valid}
        for name in ("index_out_of_range", "repeated_index", "nonfinite_coordinates", "degenerate_faces",
                     "nonmanifold_edges", "nonmanifold_vertices", "inconsistent_orientation_edges",
                     "unreferenced_vertices"):
            val[name] = getattr(report, name)
        val["first_error"] = None if valid else report.first_message.decode("utf-8", "replace")
        val["first_status"] = None if valid else L.cf_status_name(report.first_status).decode()
        out["validation"] = val
        if not valid:
            return out
        m = c_void_p()
        ctx.check(L.cf_mesh_create(ctx.ptr, byref(desc), byref(m)))
        ctx.defer(L.cf_mesh_destroy, m)
        for key, fn in (("edges", "edge_count"), ("components", "component_count"),
                        ("boundary_loops", "boundary_loop_count"), ("euler_characteristic", "euler_characteristic"),
                        ("genus", "genus")):
            out[key] = getattr(L, "cf_mesh_" + fn)(m)
        q = _lib.MeshQuality()
        ctx.check(L.cf_mesh_quality_compute(ctx.ptr, m, None, byref(q)))
        deg = 180.0 / math.pi
        out["angles"] = {"min_degrees": q.min_angle * deg, "median_degrees": q.median_angle * deg,
                         "max_degrees": q.max_angle * deg,
                         "fraction_below_10_degrees": q.fraction_angles_below_10_degrees,
                         "median_face_min_degrees": q.median_face_min_angle * deg,
                         "fraction_faces_min_below_10_degrees": q.fraction_faces_min_below_10_degrees}
        out["face_areas"] = {"total": q.total_area, "min": q.min_face_area, "median": q.median_face_area,
                             "max": q.max_face_area, "max_over_min": q.max_face_area / q.min_face_area}
        closed = out["boundary_loops"] == 0
        out["willmore_over_4pi"] = q.willmore_over_4pi if closed else None
        out["volume"] = q.volume if closed else None
        return out
