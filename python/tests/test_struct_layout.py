"""The ctypes structures that the library fills must be at least as large
as the C ones: a shorter one is written past its end. Session 29:
cf_write_options grew (OBJ materials) while the package kept the old
three fields, and cf_write_options_default's memset overwrote Python's
heap (a crash in a later test's garbage collection). Each filler writes
into a buffer with a guard band after the ctypes size, which must stay
untouched."""
import ctypes

import curvflow
from curvflow import _lib


def guarded(struct_type, fill):
    n = ctypes.sizeof(struct_type)
    buf = (ctypes.c_ubyte * (n + 256))(*([0xAB] * (n + 256)))
    fill(ctypes.cast(buf, ctypes.POINTER(struct_type)))
    return bytes(buf[n:])


def test_write_options_default_fits():
    tail = guarded(_lib.WriteOptions, lambda p: _lib.lib().cf_write_options_default(p))
    assert tail == b"\xab" * 256


def test_flow_options_default_fits():
    for kind in range(len(curvflow.methods())):
        tail = guarded(_lib.FlowOptions, lambda p: _lib.lib().cf_flow_options_default(kind, p))
        assert tail == b"\xab" * 256, kind


def test_weld_report_fits():
    """cf_weld_map clears the whole report (memset) before filling it."""
    V = (ctypes.c_double * 9)(0, 0, 0, 1, 0, 0, 0, 1, 0)
    F = (ctypes.c_int32 * 3)(0, 1, 2)
    index = (ctypes.c_int32 * 3)()
    ctx = ctypes.c_void_p()
    L = _lib.lib()
    assert L.cf_context_create(ctypes.byref(ctx)) == 0
    try:
        tail = guarded(_lib.WeldReport, lambda p: L.cf_weld_map(ctx, 3, V, 1, F, index, p))
    finally:
        L.cf_context_destroy(ctypes.byref(ctx))
    assert tail == b"\xab" * 256
