"""How the module behaves as a Python citizen: arrays without copies that keep their owner,
the GIL released during long calls, Ctrl-C, progress callbacks, help and typing."""

import gc
import os
import signal
import subprocess
import sys
import textwrap
import threading
import time
import weakref

import numpy as np
import pytest
import trochomill as tm

from conftest import ROOT

SMALL_SIM = {"simulation.resolution": 0.05, "simulation.steps_per_rev": 120, "slot.length": 6.0}


def test_arrays_are_not_copies_and_keep_their_owner(wagih):
    path = tm.plan(tm.Job.from_toml(wagih))
    gone = weakref.ref(path)
    samples = path.sample(dt_s=0.01)
    x = samples["x_mm"]
    expected = x.copy()
    # The array views memory the module made (a capsule owns it), not a copy numpy owns.
    assert not x.flags.owndata
    assert type(x.base).__name__ == "PyCapsule"
    view = x[::3]
    del path, samples, x
    gc.collect()
    assert gone() is None  # the Path is gone...
    np.testing.assert_array_equal(view, expected[::3])  # ...its samples live on
    # Many arrays made and dropped: memory returns (no leak of the owned vectors).
    for _ in range(3):
        tm.analyze(tm.Job.from_toml(wagih, set={"slot.length": 8.0}))["series"]["t_s"]
    gc.collect()


def test_series_dtypes_and_shapes(bergmann):
    job = tm.Job.from_toml(bergmann, set=SMALL_SIM)
    f = tm.forces(job, from_s=45.6, to_s=45.9)["series"]
    n = len(f["t_s"])
    assert all(f[k].dtype == np.float64 and f[k].shape == (n,) for k in
               ["t_s", "f_x_n", "f_y_n", "f_z_n", "f_resultant_n", "torque_nm", "power_w"])
    assert f["tooth_f_x_n"].shape == (n, 2) and f["tooth_f_x_n"].flags.c_contiguous


def test_the_gil_is_released_during_simulate(bergmann):
    job = tm.Job.from_toml(bergmann, set={**SMALL_SIM, "simulation.threads": 1})
    count = 0
    stop = threading.Event()

    def spin():
        nonlocal count
        while not stop.is_set():
            count += 1

    worker = threading.Thread(target=spin)
    worker.start()
    time.sleep(0.2)
    start, t0 = count, time.perf_counter()
    time.sleep(0.5)  # the spinner's rate with the GIL free
    free_rate = (count - start) / (time.perf_counter() - t0)
    start, t0 = count, time.perf_counter()
    tm.simulate(job, cycles=(1, 2))
    busy_rate = (count - start) / (time.perf_counter() - t0)
    stop.set()
    worker.join()
    # Holding the GIL, the call would stop the spinner (a thread in C code keeps it: the
    # rate would be ~0). Released, the spinner runs beside it; 10 % of its free rate leaves
    # room for the machine's other load (two cores shared with the simulation's thread).
    assert busy_rate > 0.1 * free_rate, (busy_rate, free_rate)


def test_ctrl_c_raises_keyboard_interrupt_promptly(bergmann):
    script = textwrap.dedent("""
        import sys, time
        import trochomill as tm
        job = tm.Job.from_toml(sys.argv[1])
        print("started", flush=True)
        try:
            tm.simulate(job, cycles=(3, 4))  # minutes at the example's 0.005 mm spacing
        except KeyboardInterrupt:
            print("interrupted", flush=True)
            sys.exit(3)
        print("finished", flush=True)
    """)
    env = dict(os.environ)
    p = subprocess.Popen([sys.executable, "-c", script, str(bergmann)], stdout=subprocess.PIPE,
                         stderr=subprocess.PIPE, text=True, env=env)
    assert p.stdout.readline().strip() == "started"
    # Wait until the call has run a while (CPU time of the process: the machine may be
    # loaded), then Ctrl-C.
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline:
        with open(f"/proc/{p.pid}/stat") as f:
            fields = f.read().rsplit(")", 1)[1].split()
        if (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK") > 1.5:
            break
        time.sleep(0.1)
    sent = time.monotonic()
    p.send_signal(signal.SIGINT)
    out, err = p.communicate(timeout=30)
    latency = time.monotonic() - sent
    assert p.returncode == 3, err
    assert out.strip() == "interrupted"
    # The wait polls signals every 50 ms and the simulation checks its flag every step (a
    # few ms at this spacing); 2 s allows for a loaded machine.
    assert latency < 2.0, latency


def test_progress_hears_phases_and_its_exception_stops_the_call(bergmann):
    job = tm.Job.from_toml(bergmann, set=SMALL_SIM)
    calls = []
    tm.simulate(job, cycles=(1, 2), progress=lambda phase, done, total: calls.append((phase, done, total)))
    phases = [c[0] for c in calls]
    assert "window" in phases
    assert all(done <= total for _, done, total in calls if total > 0)

    class Stop(Exception):
        pass

    def stop(phase, done, total):
        if phase == "window" and done > 0:
            raise Stop(phase)

    with pytest.raises(Stop):
        tm.simulate(job, cycles=(1, 2), progress=stop)


def test_help_and_stub_name_every_function_with_units():
    for name in tm.__all__:
        obj = getattr(tm, name)
        if callable(obj) and not isinstance(obj, type):
            assert obj.__doc__ and len(obj.__doc__) > 80, name
    assert "_mm" in tm.analyze.__doc__ and "progress" in tm.analyze.__doc__
    stub = (ROOT / "bindings" / "python" / "trochomill" / "__init__.pyi").read_text()
    for name in tm.__all__:
        if name != "__version__":
            assert f"def {name}(" in stub or f"class {name}" in stub, name
    assert tm.InputError.__module__ == "trochomill" and issubclass(tm.InputError, ValueError)
    # The stub's signatures name the same arguments as the functions (help() shows them).
    import ast
    tree = ast.parse(stub)
    stubbed = {n.name: [a.arg for a in n.args.args + n.args.kwonlyargs]
               for n in tree.body if isinstance(n, ast.FunctionDef)}
    for name, args in stubbed.items():
        doc = getattr(tm, name).__doc__.splitlines()[0]
        for arg in args:
            assert f"{arg}:" in doc, (name, arg, doc)


def test_memory_limit_refuses_before_running(bergmann):
    job = tm.Job.from_toml(bergmann)
    with pytest.raises(tm.InputError, match="simulate: estimated memory .* exceeds the limit of 1.00 kB"):
        tm.simulate(job, memory_limit_gb=1e-6)
    with pytest.raises(tm.InputError, match="memory_limit_gb must be a finite number > 0"):
        tm.plan(job, memory_limit_gb=-1.0)
