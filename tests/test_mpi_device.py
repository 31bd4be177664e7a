"""Device arrays over MPI processes: one device per process, and the ghost cells of a space
run on a device, staged through host buffers or handed to a CUDA-aware MPI.

- :meth:`granframe_cupy.CuPyBackend.for_process` puts the process of local rank r on
  device (device + r) mod devices (:func:`granframe_cupy.device_for`), checked with a
  fake device count and a fake CuPy namespace (no GPU here);
- the MPI communicator (plugins/granframe_mpi) stages a device array through a host
  buffer, one device->host copy per send and one host->device copy per receive, or hands
  it to MPI as it is when told the MPI is CUDA-aware; checked in-process on a loopback
  fake of MPI, and on 2 real MPI processes (``mpiexec -n 2``) stepping a periodic space
  run on the counting backend (:class:`granframe.testing.transfers.CountingBackend`)
  whose device arrays look like CuPy's (``__cuda_array_interface__``).

The per-step copies of each of the 2 processes of a periodic interval (both ends of its
range owned by the other process): the record vector (1 device->host copy), and for the
host-staged halo 6 exchanges per step (the two SSP-RK3 transports of the Strang step, 3
stages each) of 2 messages each (left and right), each message one device->host copy
(send) and one host->device copy (receive): 1 + 12 = 13 device->host and 12 host->device
copies per step; with a CUDA-aware MPI 1 and 0. The MPI tests skip, saying why, where
``mpiexec`` cannot start 2 processes.
"""

import json
import os
import pathlib
import shutil
import subprocess
import sys
import textwrap

import numpy
import pytest

import granframe_cupy
import granframe_mpi
from granframe.testing.transfers import CountingBackend, CudaLikeArray, DeviceArray
from granframe_cupy import CuPyBackend, device_for

#: the space run of the MPI tests: periodic, 16 cells of which each of 2 processes owns 8
#: (2 blocks of 4), WENO5 (3 ghost cells), a small 2D grid
TOML = """
final_time = 0.02
time_step = 0.004
knudsen = 0.1
integrator = "penalised_ars222"
heat_bath = 0.05
[grid]
dimension = 2
n_modes = 16
support_radius = 3.4
[kernel]
name = "hard_spheres"
[restitution]
name = "constant"
value = 0.8
[initial]
name = "riemann"
left = {density = 1.0, velocity = 0.2, temperature = 1.0}
right = {density = 0.5, temperature = 0.8}
[operator]
name = "fast_spectral"
quadrature = "review"
[space]
cells = 16
block_cells = 4
reconstruction = "weno5"
left = "periodic"
right = "periodic"
"""

#: steps counted after one warm-up step (in which constant arrays are made once)
STEPS = 3
#: ghost messages (exchanges x sides) per step of a process whose both ends are remote
MESSAGES = 6 * 2

#: the script each process runs: ``run(communicator)`` steps the space run of ``TOML`` on a
#: counting backend with CuPy-like device arrays and returns the copies of each step of
#: each process (``steps[rank][step]``, step 0 the warm-up) and f of every cell; as a
#: program, under mpiexec, it runs both MPI variants (host-staged and CUDA-aware) and
#: process 0 writes them into the JSON file named by its argument
SCRIPT = textwrap.dedent('''
    import json
    import sys

    import numpy

    from granframe.run.description import RunDescription
    from granframe.run.problems.space import SpaceProblem
    from granframe.testing.transfers import CountingBackend

    TOML = {toml!r}
    STEPS = {steps}


    def run(communicator):
        description = RunDescription.from_toml(TOML)
        backend = CountingBackend(cuda_interface=True)
        original = RunDescription.build

        def build(self, field, **extra):
            return backend if field == "backend" else original(self, field, **extra)

        RunDescription.build = build
        try:
            problem = SpaceProblem(description, communicator=communicator)
        finally:
            RunDescription.build = original
        halo, dt = problem.domain.neighbours, description.time_step
        state = problem.state(problem.f0)
        steps = []
        for k in range(STEPS + 1):               # step 0: the warm-up
            since, exchanges = len(backend.log), halo.exchanges if halo else 0
            state = problem.step(k * dt, state, dt)
            record = problem.record(state)
            entries = backend.log[since:]
            steps.append({{**backend.counts(since),
                          "exchanges": (halo.exchanges if halo else 0) - exchanges,
                          "to_host_shapes": [list(e[1]) for e in entries
                                             if e[0] == "to_host"],
                          "mass": float(record["mass"]),
                          "energy": float(record["kinetic_energy"])}})
        f = numpy.concatenate(communicator.allgather_object(problem.snapshot(state)))
        return {{"steps": communicator.allgather_object(steps), "f": f.tolist(),
                "processes": communicator.size, "array": type(state).__name__}}


    if __name__ == "__main__":
        from granframe_mpi import MPICommunicator

        results = {{}}
        for name, aware in (("staged", False), ("aware", True)):
            communicator = MPICommunicator(device_aware=aware)
            results[name] = run(communicator)
        if communicator.rank == 0:
            with open(sys.argv[1], "w") as file:
                json.dump(results, file)
''').format(toml=TOML, steps=STEPS)


# -- one device per process ---------------------------------------------------------------

def test_device_for_takes_the_devices_in_turn_from_the_first():
    assert [device_for(r, 4) for r in range(6)] == [0, 1, 2, 3, 0, 1]
    assert [device_for(r, 4, first=2) for r in range(4)] == [2, 3, 0, 1]
    assert [device_for(r, 1) for r in range(3)] == [0, 0, 0]   # one visible device each
    assert device_for(0, 8, first=5) == 5                      # a serial run keeps its device


@pytest.mark.parametrize("arguments", [(0, 0), (-1, 2), (0, 2, 2), (1.5, 2), (0, 2, -1)])
def test_device_for_refuses_what_is_not_a_device(arguments):
    with pytest.raises(ValueError):
        device_for(*arguments)


class _FakeCuda:
    """The parts of ``cupy`` that the backend's construction and :meth:`for_process` use,
    on ``count`` fake devices: which device is current, which were selected, the memory
    limits set (device, bytes)."""

    def __init__(self, count):
        self.current, self.selected, self.limits = 0, [], []
        fake = self

        class Runtime:
            @staticmethod
            def getDeviceCount():
                return count

            @staticmethod
            def getDevice():
                return fake.current

        class Device:
            def __init__(self, number):
                self.number = number

            def use(self):
                fake.current = self.number
                fake.selected.append(self.number)

        class Pool:
            def set_limit(self, size):
                fake.limits.append((fake.current, size))

        self.cuda = type("cuda", (), {"runtime": Runtime, "Device": Device})
        self.get_default_memory_pool = Pool


@pytest.fixture
def fake_cupy(monkeypatch):
    """A CuPy of 3 devices behind ``CuPyBackend(module="cupy")``."""
    fake = _FakeCuda(3)
    monkeypatch.setattr(granframe_cupy, "_import", lambda module: (fake, None))
    return fake


def test_each_process_of_a_host_gets_the_next_device(fake_cupy):
    """What every process does (SpaceProblem): build the described backend, then take its
    own; the first builds no context on device 0 that the others would leave behind."""
    devices = []
    for rank in range(5):                      # a fresh process each: device 0 current
        fake_cupy.current, fake_cupy.selected = 0, []
        backend = CuPyBackend(memory_limit=2 ** 20)
        assert fake_cupy.selected == []        # device 0 is current already: left as it is
        own = backend.for_process(rank)
        assert isinstance(own, CuPyBackend) and own.memory_limit == 2 ** 20
        assert (own is backend) == (own.device == 0)
        assert fake_cupy.selected == ([] if own.device == 0 else [own.device])
        assert fake_cupy.current == own.device and fake_cupy.limits[-1] == (own.device, 2 ** 20)
        devices.append(own.device)
    assert devices == [0, 1, 2, 0, 1]


def test_a_given_device_is_the_first_process_s(fake_cupy):
    backend = CuPyBackend(device=2)
    assert fake_cupy.selected == [2]
    assert [backend.for_process(r).device for r in range(3)] == [2, 0, 1]


def test_the_host_code_path_is_shared_by_every_process():
    backend = CuPyBackend(module="numpy")
    assert backend.for_process(3) is backend


# -- the MPI plugin without MPI -----------------------------------------------------------

@pytest.mark.parametrize("environ,aware", [
    ({}, False),
    ({"GRANFRAME_CUDA_AWARE_MPI": "1"}, True),
    ({"GRANFRAME_CUDA_AWARE_MPI": " 1 "}, True),
    ({"GRANFRAME_CUDA_AWARE_MPI": "0"}, False),
    ({"MPIR_CVAR_ENABLE_GPU": "1"}, True),
    ({"MPIR_CVAR_ENABLE_GPU": "0"}, False),
    ({"GRANFRAME_CUDA_AWARE_MPI": "0", "MPIR_CVAR_ENABLE_GPU": "1"}, False),   # ours first
    ({"GRANFRAME_CUDA_AWARE_MPI": "1", "MPIR_CVAR_ENABLE_GPU": "0"}, True),
    ({"GRANFRAME_CUDA_AWARE_MPI": "yes", "MPIR_CVAR_ENABLE_GPU": "1"}, True),  # not 0/1: MPICH's
    ({"GRANFRAME_CUDA_AWARE_MPI": "", "MPIR_CVAR_ENABLE_GPU": ""}, False),
])
def test_cuda_aware_reads_the_environment(environ, aware):
    assert granframe_mpi.cuda_aware(environ) is aware


def test_cuda_aware_reads_os_environ_by_default(monkeypatch):
    monkeypatch.delenv("MPIR_CVAR_ENABLE_GPU", raising=False)
    monkeypatch.setenv("GRANFRAME_CUDA_AWARE_MPI", "1")
    assert granframe_mpi.cuda_aware()
    monkeypatch.setenv("GRANFRAME_CUDA_AWARE_MPI", "0")
    assert not granframe_mpi.cuda_aware()


def test_cuda_like_device_arrays_are_taken_for_device_arrays():
    plain, like = CountingBackend(), CountingBackend(cuda_interface=True)
    a, b = plain.xp.zeros((2, 5, 3)), like.xp.zeros((2, 5, 3))
    assert not granframe_mpi.on_device(a)
    assert isinstance(b, CudaLikeArray) and isinstance(b, DeviceArray)
    for view in (b[0, 1:3], b + 1.0, like.xp.ascontiguousarray(b[:, 2])):
        assert isinstance(view, CudaLikeArray) and granframe_mpi.on_device(view)
    interface = b[1, 1:3].__cuda_array_interface__
    assert interface["shape"] == (2, 3) and interface["version"] == 3
    assert interface["data"][0] == b[1, 1:3].__array_interface__["data"][0]
    buffer = granframe_mpi.host_buffer(b[0, 1:3])     # not CuPy's: plain host memory
    assert type(buffer) is numpy.ndarray and buffer.shape == (2, 3)
    assert like.counts() == {"to_host": 0, "to_device": 0}


def test_get_into_a_buffer_and_set_from_one_are_counted_copies():
    backend = CountingBackend(cuda_interface=True)
    a = backend.xp.arange(12.0).reshape(3, 4)
    out = numpy.empty(4)
    assert a[1].get(out=out) is out and out.tolist() == [4.0, 5.0, 6.0, 7.0]
    a[2].set(numpy.full(4, -1.0))
    assert a[2].tolist() == [-1.0] * 4              # one more device->host copy
    assert backend.counts() == {"to_host": 2, "to_device": 1}
    for bad, error in ((numpy.empty(3), ValueError), (numpy.empty(4, int), TypeError),
                       (backend.xp.empty(4), TypeError)):
        with pytest.raises(error):
            a[0].get(out=bad)
        with pytest.raises(error):
            a[0].set(bad)
    with pytest.raises(RuntimeError):
        a[:, 0].set(numpy.zeros(3))                # CuPy refuses a non-contiguous target
    assert backend.counts() == {"to_host": 2, "to_device": 1}


class _Loopback:
    """mpi4py's ``MPI`` and ``COMM_WORLD`` for one process sending to itself: the sends
    are copied when posted, the receives filled at ``Waitall``; what MPI was handed is kept
    in ``handed``."""

    def __init__(self):
        self.sent, self.receives, self.handed = {}, [], []
        loop = self

        class Request:
            @staticmethod
            def Waitall(requests):
                for buffer, source, tag in loop.receives:
                    buffer[...] = loop.sent.pop((source, tag))
                loop.receives.clear()

        self.Request = Request

    def Isend(self, array, dest, tag):
        self.handed.append(array)
        self.sent[(dest, tag)] = numpy.array(array)

    def Irecv(self, array, source, tag):
        self.handed.append(array)
        self.receives.append((array, source, tag))


def _loopback_communicator(aware):
    communicator = object.__new__(granframe_mpi.MPICommunicator)
    loop = _Loopback()
    communicator.mpi = communicator.comm = loop
    communicator.rank, communicator.size, communicator.local_rank = 0, 1, 0
    communicator.device_aware, communicator._buffers = aware, {}
    return communicator, loop


@pytest.mark.parametrize("aware", [False, True])
def test_a_device_message_is_staged_unless_mpi_is_cuda_aware(aware):
    backend = CountingBackend(cuda_interface=True)
    communicator, loop = _loopback_communicator(aware)
    a = backend.xp.arange(40.0).reshape(2, 5, 4)
    for exchange in range(2):                 # the buffers are made once and reused
        backend.reset()
        loop.handed.clear()
        pending = communicator.start([(0, 0, a[0, 1:2]), (0, 1, a[-1, 3:4])],
                                     [(0, 0, a[-1, 0:1]), (0, 1, a[0, 4:5])])
        pending.wait()
        staged = {"to_host": 2, "to_device": 2}
        assert backend.counts() == ({"to_host": 0, "to_device": 0} if aware else staged)
        host = a.view(numpy.ndarray)
        assert (host[-1, 0] == host[0, 1]).all() and (host[0, 4] == host[-1, 3]).all()
        devices = [x for x in loop.handed if isinstance(x, DeviceArray)]
        assert len(devices) == (4 if aware else 0)
        assert len(communicator._buffers) == (0 if aware else 4)


def test_host_arrays_go_to_mpi_as_they_are():
    communicator, loop = _loopback_communicator(False)
    a = numpy.arange(10.0).reshape(5, 2)
    communicator.start([(0, 7, a[1])], [(0, 7, a[4])]).wait()
    assert a[4].tolist() == [2.0, 3.0] and not communicator._buffers


# -- a space run on 2 MPI processes -------------------------------------------------------

def _mpiexec():
    beside = pathlib.Path(sys.executable).with_name("mpiexec")
    return str(beside) if beside.exists() else shutil.which("mpiexec")


@pytest.fixture(scope="module")
def mpiexec():
    """The mpiexec that starts 2 processes of this Python with mpi4py, or a skip saying
    why not (probed once, with a timeout)."""
    launcher = _mpiexec()
    if launcher is None:
        pytest.skip("no mpiexec beside this Python or on PATH (pip install 'granframe[mpi]')")
    # rank 0 alone prints: two ranks' lines can interleave ("22") when the machine is busy
    probe = ("from mpi4py import MPI; world = MPI.COMM_WORLD; "
             "world.Get_rank() == 0 and print(world.Get_size())")
    try:
        done = subprocess.run([launcher, "-n", "2", sys.executable, "-c", probe],
                              capture_output=True, text=True, timeout=60)
    except (OSError, subprocess.TimeoutExpired) as exc:
        pytest.skip(f"{launcher} -n 2 cannot start 2 processes here: {exc}")
    if done.returncode != 0 or done.stdout.split() != ["2"]:
        pytest.skip(f"{launcher} -n 2 did not start 2 MPI processes of one world "
                    f"(exit {done.returncode}, out {done.stdout.strip()!r}, "
                    f"err {done.stderr.strip()[-300:]!r})")
    return launcher


@pytest.fixture(scope="module")
def runs(mpiexec, tmp_path_factory):
    """The run on 2 processes, host-staged and CUDA-aware, and on 1 (serial, here)."""
    folder = tmp_path_factory.mktemp("mpi_device")
    script, output = folder / "space_step.py", folder / "result.json"
    script.write_text(SCRIPT)
    environ = {k: v for k, v in os.environ.items()
               if k not in ("GRANFRAME_CUDA_AWARE_MPI", "MPIR_CVAR_ENABLE_GPU")}
    environ["OMP_NUM_THREADS"] = "1"
    done = subprocess.run([mpiexec, "-n", "2", sys.executable, str(script), str(output)],
                          capture_output=True, text=True, timeout=240, env=environ,
                          cwd=folder)
    assert done.returncode == 0, done.stdout[-2000:] + done.stderr[-4000:]
    results = json.loads(output.read_text())
    namespace = {"__name__": "space_step"}
    exec(compile(SCRIPT, str(script), "exec"), namespace)
    from granframe.parallel import SerialCommunicator

    results["serial"] = namespace["run"](SerialCommunicator())
    return results


@pytest.mark.parametrize("name", ["staged", "aware"])
def test_two_processes_give_the_serial_result(runs, name):
    serial, spread = runs["serial"], runs[name]
    assert serial["processes"] == 1 and spread["processes"] == 2
    assert spread["array"] == "CudaLikeArray"
    f, g = numpy.array(serial["f"]), numpy.array(spread["f"])
    assert f.shape == g.shape == (16, 16, 16)
    assert numpy.max(numpy.abs(f - g)) <= 1e-12 * numpy.max(numpy.abs(f))
    for a, b in zip(serial["steps"][0], spread["steps"][0]):
        for total in ("mass", "energy"):
            assert abs(a[total] - b[total]) <= 1e-12 * abs(a[total]), total


def test_the_aware_and_the_staged_messages_carry_the_same_data(runs):
    assert runs["staged"]["f"] == runs["aware"]["f"]


def test_a_staged_step_copies_each_ghost_message_once_each_way(runs):
    """Per step and process: the record vector and 12 ghost messages (6 exchanges x 2
    sides) down, the 12 messages up."""
    steps = runs["staged"]["steps"]
    assert len(steps) == 2
    for step in steps[0][1:] + steps[1][1:]:
        assert step["exchanges"] == 6
        assert step["to_host"] == 1 + MESSAGES == 13, step
        assert step["to_device"] == MESSAGES == 12, step
        shapes = sorted(map(tuple, step["to_host_shapes"]))
        ghost = (3, 16, 16)                           # WENO5: 3 cells of a 16 x 16 grid
        assert shapes.count(ghost) == MESSAGES and len(set(shapes) - {ghost}) == 1


@pytest.mark.parametrize("name", ["aware", "serial"])
def test_an_aware_or_serial_step_copies_the_record_alone(runs, name):
    steps = runs[name]["steps"]
    assert len(steps) == (2 if name == "aware" else 1)
    for step in [step for process in steps for step in process[1:]]:
        assert step["exchanges"] == (6 if name == "aware" else 0)
        assert (step["to_host"], step["to_device"]) == (1, 0), step
