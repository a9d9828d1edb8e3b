"""ctypes declarations of the public C API (include/curvflow/*.h) and the
search for libcurvflow.so.

Where the library is looked for, first match wins:
  1. $CURVFLOW_LIB_DIR (an error if it is set and holds no library: an
     explicit choice is never silently replaced by another copy);
  2. the copy installed inside this package (``pip install ./python``);
  3. the build tree: $BUILD_DIR, then <checkout>/build (CMake target
     curvflow_shared);
  4. the system's search path (ld.so: LD_LIBRARY_PATH, /usr/local/lib ...).

Structures below mirror the C headers field by field; the method options
with pointer fields (cf_spin_willmore_options, cf_stretch_bend_options) are
checked against the library's own parameter table before they are used
(check_options_layout), so a header change cannot silently write to the
wrong place.
"""
import ctypes
import ctypes.util
import os
import pathlib
import threading
from ctypes import (CFUNCTYPE, POINTER, Structure, c_char, c_char_p, c_double, c_int, c_int32, c_int64,
                    c_size_t, c_void_p)

from . import _blas_kernels
from .errors import LibraryNotFoundError

# The major.minor the mirrors below were written for (CF_VERSION_*).
ABI_VERSION = (0, 1)

_SONAMES = ("libcurvflow.so.0", "libcurvflow.so")
_PACKAGE_DIR = pathlib.Path(__file__).resolve().parent
_CHECKOUT = _PACKAGE_DIR.parent.parent  # python/curvflow -> repository root


# ---- structures -----------------------------------------------------------

class MeshDesc(Structure):
    _fields_ = [("vertex_count", c_int32), ("positions", c_void_p), ("face_count", c_int32),
                ("triangles", c_void_p), ("uv_count", c_int32), ("uv", c_void_p), ("uv_triangles", c_void_p)]


class MeshProperty(Structure):
    _fields_ = [("name", c_char_p), ("values", POINTER(c_double))]


class MeshData(Structure):
    _fields_ = [("vertex_count", c_int32), ("positions", POINTER(c_double)), ("face_count", c_int32),
                ("triangles", POINTER(c_int32)), ("uv_count", c_int32), ("uv", POINTER(c_double)),
                ("uv_triangles", POINTER(c_int32)), ("vertex_property_count", c_int32),
                ("vertex_properties", POINTER(MeshProperty)), ("face_property_count", c_int32),
                ("face_properties", POINTER(MeshProperty)), ("polygon_count", c_int32), ("context", c_void_p),
                ("material_library_count", c_int32), ("material_libraries", c_void_p), ("material_count", c_int32),
                ("material_names", c_void_p), ("face_materials", c_void_p)]


class MeshReport(Structure):
    _fields_ = [("index_out_of_range", c_int32), ("repeated_index", c_int32),
                ("nonfinite_coordinates", c_int32), ("degenerate_faces", c_int32),
                ("nonmanifold_edges", c_int32), ("nonmanifold_vertices", c_int32),
                ("inconsistent_orientation_edges", c_int32), ("unreferenced_vertices", c_int32),
                ("first_status", c_int), ("first_message", c_char * 256)]


class WeldReport(Structure):
    _fields_ = [("candidates", c_int32), ("groups", c_int32), ("welded", c_int32), ("removed", c_int32),
                ("vertices", c_int32), ("differing_properties", c_int32), ("refused", c_char * 256)]


class Field(Structure):
    _fields_ = [("name", c_char_p), ("location", c_int), ("values", c_void_p)]


class WriteOptions(Structure):
    # cf_write_options (curvflow/io.h) field for field: cf_write_options_default writes the whole
    # C struct, so a shorter one here would be overwritten past its end
    _fields_ = [("format", c_int), ("ply_encoding", c_int), ("write_uv", c_int32),
                ("material_library_count", c_int32), ("material_libraries", c_void_p),
                ("material_count", c_int32), ("material_names", c_void_p), ("face_materials", c_void_p)]


class Stats(Structure):
    _fields_ = [("count", c_int64), ("min", c_double), ("max", c_double), ("mean", c_double),
                ("weighted_mean", c_double), ("weighted_std", c_double), ("p50", c_double), ("p95", c_double)]


class VertexScaleFit(Structure):
    _fields_ = [("q", Stats), ("invalid_faces", c_int32), ("rms_residual", c_double)]


MAX_TERMS = 4
MAX_RESIDUALS = 10


class FlowInfo(Structure):
    _fields_ = [("iteration", c_int64), ("time", c_double), ("time_step", c_double), ("energy", c_double),
                ("energy_terms", c_double * MAX_TERMS), ("term_names", c_char_p * MAX_TERMS),
                ("residuals", c_double * MAX_RESIDUALS), ("residual_names", c_char_p * MAX_RESIDUALS),
                ("area", c_double), ("volume", c_double), ("area_drift", c_double), ("volume_drift", c_double),
                ("assemble_seconds", c_double), ("factorize_seconds", c_double), ("solve_seconds", c_double),
                ("total_seconds", c_double)]


class ParamDesc(Structure):
    _fields_ = [("name", c_char_p), ("type", c_int), ("offset", c_size_t), ("min_value", c_double),
                ("max_value", c_double), ("choices", POINTER(c_char_p)), ("help", c_char_p)]


OPTIONS_STORAGE = 1024


class FlowOptions(Structure):
    # kind, then a union {double; unsigned char[1024]} (aligned to 8)
    _fields_ = [("kind", c_int), ("storage", c_double * (OPTIONS_STORAGE // 8))]


class ParamValues(Structure):
    # cf_param_values (flow.h): the field of an array-valued table parameter
    _fields_ = [("values", c_void_p), ("count", c_int32)]


class SpinWillmoreOptions(Structure):
    _fields_ = [("time_step", c_double), ("total_curvature", c_int32), ("inversion", c_int32),
                ("exactness", c_int32), ("mobius", c_int32), ("mobius_weight", c_double), ("sigma", c_double),
                ("filter_k", c_int32), ("boundary_mode", c_int32), ("boundary_angle", c_double),
                ("boundary_vector_angle", c_double), ("boundary_tangent_angle", c_double),
                ("boundary_axis", c_double * 3), ("power_iterations", c_int32), ("normalize", c_int32),
                ("tolerance", c_double), ("complex_factorization", c_int32), ("input_metric", c_int32),
                ("adaptive", c_int32),
                ("max_scale_change", c_double), ("exactness_linearized", c_int32), ("period_iterations", c_int32),
                ("period_tolerance", c_double), ("max_integrability_error", c_double), ("harmonic_update", c_int32),
                ("regularization", c_double), ("growth_ratio", c_double), ("exactness_refresh", c_double),
                ("boundary_targets", ParamValues), ("fairing", c_double), ("max_conformal_excess", c_double),
                ("stall_fairing", c_int32), ("max_realised_decrease", c_double), ("weight_floor", c_double),
                ("max_period_error", c_double), ("relaxation", c_int32), ("keep_class", c_int32),
                ("recovery_scale_weight", c_double), ("period_first_order", c_int32)]


class StretchBendOptions(Structure):
    _fields_ = [("energy", c_int32), ("lambda_", c_double), ("max_iterations", c_int32),
                ("relative_tolerance", c_double), ("mass", c_int32), ("scale_free", c_int32),
                ("anderson", c_int32), ("arap_weights", c_int32), ("handles", c_void_p),
                ("rest_positions", c_void_p)]


class HandleSet(Structure):
    _fields_ = [("count", c_int32), ("vertices", POINTER(c_int32)), ("targets", POINTER(c_double)),
                ("moved_count", c_int32), ("ctx", c_void_p)]


class ConformalClass(Structure):
    _fields_ = [("genus", c_int32), ("modulus", c_double * 2), ("intersection_error", c_double),
                ("hodge_defect", c_double)]


class ShapeSummary(Structure):
    _fields_ = [("area", c_double), ("volume", c_double), ("willmore", c_double),
                ("willmore_over_4pi", c_double), ("total_angle_defect", c_double),
                ("gauss_bonnet_target", c_double), ("sphere_center", c_double * 3), ("sphere_radius", c_double),
                ("sphere_max_deviation", c_double), ("sphere_rms_deviation", c_double)]


class MeshQuality(Structure):
    _fields_ = [(name, c_double) for name in (
        "min_angle", "median_angle", "max_angle", "fraction_angles_below_10_degrees", "median_face_min_angle",
        "fraction_faces_min_below_10_degrees", "total_area", "min_face_area", "median_face_area", "max_face_area",
        "willmore_over_4pi", "volume")]


PROGRESS_FN = CFUNCTYPE(c_int, c_void_p, POINTER(FlowInfo))
LOG_FN = CFUNCTYPE(None, c_void_p, c_int, c_char_p)

# Parameter name -> field of the mirror (name, index) for the options
# structs that have pointer fields; every named parameter of those methods
# must appear here with the library's offset before a pointer is written.
_LAYOUT = {
    "spin-willmore": (SpinWillmoreOptions, {
        "time_step": ("time_step", 0), "total_curvature": ("total_curvature", 0),
        "inversion": ("inversion", 0), "exactness": ("exactness", 0), "mobius": ("mobius", 0),
        "mobius_weight": ("mobius_weight", 0), "sigma": ("sigma", 0), "filter_k": ("filter_k", 0),
        "boundary": ("boundary_mode", 0), "boundary_angle": ("boundary_angle", 0),
        "boundary_vector_angle": ("boundary_vector_angle", 0),
        "boundary_tangent_angle": ("boundary_tangent_angle", 0), "boundary_axis_x": ("boundary_axis", 0),
        "boundary_axis_y": ("boundary_axis", 1), "boundary_axis_z": ("boundary_axis", 2),
        "power_iterations": ("power_iterations", 0), "normalize": ("normalize", 0),
        "tolerance": ("tolerance", 0), "complex_factorization": ("complex_factorization", 0),
        "input_metric": ("input_metric", 0), "adaptive": ("adaptive", 0),
        "max_scale_change": ("max_scale_change", 0),
        "exactness_linearized": ("exactness_linearized", 0), "period_iterations": ("period_iterations", 0),
        "period_tolerance": ("period_tolerance", 0), "max_integrability_error": ("max_integrability_error", 0),
        "regularization": ("regularization", 0), "growth_ratio": ("growth_ratio", 0),
        "exactness_refresh": ("exactness_refresh", 0),
        "harmonic_update": ("harmonic_update", 0), "boundary_targets": ("boundary_targets", 0),
        "fairing": ("fairing", 0), "max_conformal_excess": ("max_conformal_excess", 0),
        "stall_fairing": ("stall_fairing", 0),
        "max_realised_decrease": ("max_realised_decrease", 0), "weight_floor": ("weight_floor", 0),
        "max_period_error": ("max_period_error", 0), "relaxation": ("relaxation", 0),
        "keep_class": ("keep_class", 0), "recovery_scale_weight": ("recovery_scale_weight", 0),
        "period_first_order": ("period_first_order", 0)}),
    "stretch-bend-edit": (StretchBendOptions, {
        "energy": ("energy", 0), "lambda": ("lambda_", 0), "max_iterations": ("max_iterations", 0),
        "relative_tolerance": ("relative_tolerance", 0), "mass": ("mass", 0), "scale_free": ("scale_free", 0),
        "anderson": ("anderson", 0), "arap_weights": ("arap_weights", 0), "handles": ("handles", 0)}),
}


# ---- loading ----------------------------------------------------------------

_lock = threading.Lock()
_lib = None
_layout_checked = {}


def _find_in(directory):
    for name in _SONAMES:
        p = pathlib.Path(directory) / name
        if p.is_file():
            return p
    return None


def _search():
    env = os.environ.get("CURVFLOW_LIB_DIR")
    if env:
        yield "$CURVFLOW_LIB_DIR=%s" % env, _find_in(env)
        return  # explicit: nothing else
    yield "the installed package (%s)" % _PACKAGE_DIR, _find_in(_PACKAGE_DIR)
    build = os.environ.get("BUILD_DIR")
    if build:
        yield "$BUILD_DIR=%s" % build, _find_in(build)
    yield "the checkout's build tree (%s)" % (_CHECKOUT / "build"), _find_in(_CHECKOUT / "build")
    yield "the system library path", ctypes.util.find_library("curvflow")


def candidates():
    """The places searched, in order, as (description, path-or-None)."""
    return list(_search())


def first_candidate():
    """The library that lib() would try first, or None (for the kernels'
    question, asked before numpy is imported; the system's search path,
    slow to ask, only when nothing comes before it)."""
    return next((path for _, path in _search() if path is not None), None)


def _declare(lib):
    def f(name, restype, *argtypes):
        fn = getattr(lib, name)
        fn.restype = restype
        fn.argtypes = list(argtypes)

    P, I32, I64, D = c_void_p, c_int32, c_int64, c_double
    S = c_int  # cf_status
    # curvflow.h
    f("cf_status_name", c_char_p, S)
    f("cf_context_create", S, POINTER(c_void_p))
    f("cf_context_destroy", None, POINTER(c_void_p))
    f("cf_context_set_log", None, P, LOG_FN, P, c_int)
    f("cf_context_set_threads", S, P, I32)
    f("cf_context_message", c_char_p, P)
    f("cf_context_status", S, P)
    f("cf_context_clear_error", None, P)
    f("cf_version_string", c_char_p)
    f("cf_blas_core", c_char_p)
    f("cf_blas_core_advice", c_char_p)
    # mesh.h
    f("cf_mesh_create", S, P, POINTER(MeshDesc), POINTER(c_void_p))
    f("cf_mesh_destroy", None, POINTER(c_void_p))
    f("cf_mesh_validate", S, P, POINTER(MeshDesc), POINTER(MeshReport))
    for name in ("vertex_count", "face_count", "edge_count", "boundary_loop_count", "component_count",
                 "euler_characteristic", "genus", "uv_count"):
        f("cf_mesh_" + name, I32, P)
    f("cf_mesh_positions", POINTER(c_double), P)
    f("cf_mesh_triangles", POINTER(c_int32), P)
    f("cf_mesh_uv", POINTER(c_double), P)
    f("cf_mesh_uv_triangles", POINTER(c_int32), P)
    # ops.h
    f("cf_loop_subdivide", S, P, P, P, I32, POINTER(c_void_p))
    # io.h
    f("cf_mesh_data_destroy", None, POINTER(POINTER(MeshData)))
    f("cf_mesh_data_desc", S, POINTER(MeshData), POINTER(MeshDesc))
    f("cf_mesh_data_weld", S, c_void_p, POINTER(MeshData), c_void_p, POINTER(WeldReport))
    f("cf_weld_map", S, c_void_p, c_int32, c_void_p, c_int32, c_void_p, c_void_p, POINTER(WeldReport))
    f("cf_mesh_data_drop_unreferenced", S, c_void_p, POINTER(MeshData), c_void_p, POINTER(c_int32))
    f("cf_read_mesh_file", S, P, c_char_p, POINTER(POINTER(MeshData)))
    f("cf_write_options_default", None, POINTER(WriteOptions))
    f("cf_write_mesh_file_ex", S, P, c_char_p, P, P, POINTER(Field), I32, POINTER(WriteOptions))
    f("cf_write_text_file_atomic", S, P, c_char_p, c_char_p, c_size_t)
    f("cf_mesh_format_from_path", S, P, c_char_p, POINTER(c_int))
    f("cf_field_name_valid", I32, c_char_p)
    # flow.h
    f("cf_flow_kind_name", c_char_p, c_int)
    f("cf_flow_kind_description", c_char_p, c_int)
    f("cf_flow_kind_from_name", S, c_char_p, POINTER(c_int))
    f("cf_flow_options_default", S, c_int, POINTER(FlowOptions))
    f("cf_flow_options_set", S, P, POINTER(FlowOptions), c_char_p, c_char_p)
    f("cf_flow_options_format", S, POINTER(FlowOptions), POINTER(ParamDesc), c_char_p, c_size_t)
    f("cf_flow_params", S, c_int, POINTER(POINTER(ParamDesc)), POINTER(c_int32))
    f("cf_flow_common_params", S, POINTER(POINTER(ParamDesc)), POINTER(c_int32))
    f("cf_flow_param_range_format", S, POINTER(ParamDesc), c_char_p, c_size_t)
    f("cf_flow_create", S, P, P, P, POINTER(FlowOptions), POINTER(c_void_p))
    f("cf_flow_create_at", S, P, P, P, POINTER(FlowOptions), POINTER(c_void_p))
    f("cf_flow_run", S, P, I64, POINTER(FlowInfo))
    f("cf_flow_set_progress", None, P, PROGRESS_FN, P)
    f("cf_flow_positions", POINTER(c_double), P)
    f("cf_flow_last_info", POINTER(FlowInfo), P)
    f("cf_flow_converged", I32, P)
    f("cf_flow_destroy", None, POINTER(c_void_p))
    # stretch_bend_edit.h
    f("cf_handle_set_create", S, P, I32, P, P, POINTER(POINTER(HandleSet)))
    f("cf_handle_set_destroy", None, POINTER(POINTER(HandleSet)))
    f("cf_handle_set_read_json", S, P, P, P, c_char_p, POINTER(POINTER(HandleSet)))
    f("cf_handle_set_parse_json", S, P, P, P, c_char_p, c_char_p, POINTER(POINTER(HandleSet)))
    # spin_willmore.h
    f("cf_spin_transform", S, P, P, P, P, P)
    # metrics.h
    f("cf_quasi_conformal_error", S, P, P, P, P, P, POINTER(Stats))
    f("cf_log_area_distortion", S, P, P, P, P, P, POINTER(Stats))
    f("cf_angle_change", S, P, P, P, P, P, POINTER(Stats))
    f("cf_vertex_scale_fit_compute", S, P, P, P, P, P, P, POINTER(VertexScaleFit))
    f("cf_conformal_class_compute", S, P, P, P, P, POINTER(ConformalClass))
    f("cf_conformal_class_distance", S, P, P, P, P, POINTER(ConformalClass), POINTER(ConformalClass), POINTER(D))
    f("cf_shape_summary_compute", S, P, P, P, POINTER(ShapeSummary))
    f("cf_mesh_quality_compute", S, P, P, P, POINTER(MeshQuality))
    # ops.h
    f("cf_corner_angles", S, P, P, P, P)
    f("cf_face_areas", S, P, P, P, P)
    f("cf_willmore_energy", S, P, P, P, POINTER(D))
    f("cf_enclosed_volume", S, P, P, P, POINTER(D))
    f("cf_total_area", S, P, P, P, POINTER(D))
    return lib


def lib():
    """The loaded library (loaded on first use). Raises LibraryNotFoundError
    naming every place searched."""
    global _lib
    if _lib is not None:
        return _lib
    with _lock:
        if _lib is not None:
            return _lib
        tried = []
        for where, path in candidates():
            if path is None:
                tried.append("%s: no libcurvflow.so" % where)
                continue
            try:
                loaded = ctypes.CDLL(str(path))
            except OSError as e:
                tried.append("%s: %s" % (where, e))
                if os.environ.get("CURVFLOW_LIB_DIR"):
                    break
                continue
            _declare(loaded)
            version = loaded.cf_version_string().decode()
            major_minor = tuple(int(x) for x in version.split(".")[:2])
            if major_minor != ABI_VERSION:
                tried.append("%s: version %s, this package needs %d.%d.x" % ((where, version) + ABI_VERSION))
                continue
            _blas_kernels.settle_after_loading(loaded)
            loaded.curvflow_path = str(path)
            _lib = loaded
            return _lib
        raise LibraryNotFoundError(
            "libcurvflow.so not found or not loadable; build it (cmake --build build, target curvflow_shared) "
            "or set CURVFLOW_LIB_DIR to the directory holding it. Searched: " + "; ".join(tried))


def check_options_layout(method):
    """Verifies the ctypes mirror of `method`'s options struct against the
    library's parameter table (names and byte offsets). Returns the mirror
    class; raises UnsupportedError when they disagree."""
    from .errors import UnsupportedError
    mirror, names = _LAYOUT[method]
    if method in _layout_checked:
        return _layout_checked[method]
    L = lib()
    kind = c_int()
    L.cf_flow_kind_from_name(method.encode(), ctypes.byref(kind))
    table = POINTER(ParamDesc)()
    count = c_int32()
    L.cf_flow_params(kind.value, ctypes.byref(table), ctypes.byref(count))
    problems = []
    for i in range(count.value):
        p = table[i]
        name = p.name.decode()
        if name not in names:
            problems.append("parameter %s is unknown to the mirror" % name)
            continue
        field, index = names[name]
        descr = getattr(mirror, field)
        elem = ctypes.sizeof(c_double) if index else 0
        if descr.offset + index * elem != p.offset:
            problems.append("%s at offset %d, mirror %d" % (name, p.offset, descr.offset + index * elem))
    if problems:
        raise UnsupportedError("curvflow's ctypes mirror of the %s options does not match the library (%s); "
                               "the Python package and libcurvflow.so are from different versions"
                               % (method, "; ".join(problems)))
    _layout_checked[method] = mirror
    return mirror
