"""The pieces of a run over processes that need no MPI (granframe.parallel).

How many processes a launcher started (read from its environment, nothing imported); the
cells each process owns (contiguous whole chunks, refusals naming the parameter); the
serial communicator; the ghost cells of three domains exchanged through a communicator
that matches messages by (peer, tag), equal to one domain owning every cell; the core
never importing mpi4py; and the refusals of :func:`granframe.parallel.world` when a
launcher started several processes that MPI cannot serve.
"""

import os
import subprocess
import sys
import textwrap
import threading

import numpy
import pytest

import granframe as gf
import granframe.parallel as parallel
from granframe.abc import Communicator, Pending
from granframe.parallel import (LEFTWARD, RIGHTWARD, Halo, SerialCommunicator, launched,
                                partition, world)
from granframe.space.boundaries import Diffuse, Periodic, Specular
from granframe.space.domain import Domain
from granframe.space.reconstruction import WENO5
from granframe.testing import conformance as kit

# -- launched() -------------------------------------------------------------------------------

@pytest.mark.parametrize("environ, expected", [
    ({}, (1, 0, None)),
    ({"PMI_SIZE": "4", "PMI_RANK": "2"}, (4, 2, "PMI_SIZE")),                # Hydra, Intel
    ({"OMPI_COMM_WORLD_SIZE": "3", "OMPI_COMM_WORLD_RANK": "1"},
     (3, 1, "OMPI_COMM_WORLD_SIZE")),                                        # Open MPI
    ({"MV2_COMM_WORLD_SIZE": "2", "MV2_COMM_WORLD_RANK": "1"},
     (2, 1, "MV2_COMM_WORLD_SIZE")),                                         # MVAPICH
    ({"SLURM_STEP_NUM_TASKS": "8", "SLURM_PROCID": "5"}, (8, 5, "SLURM_STEP_NUM_TASKS")),
    # a batch script's allocation is not a launch: srun sets the step's variables
    ({"SLURM_NTASKS": "8", "SLURM_PROCID": "0"}, (1, 0, None)),
    ({"SLURM_NTASKS": "8", "SLURM_NPROCS": "8", "SLURM_JOB_NUM_NODES": "2"}, (1, 0, None)),
    # one process launched (mpiexec -n 1) is a serial run
    ({"PMI_SIZE": "1", "PMI_RANK": "0"}, (1, 0, None)),
    ({"PMI_SIZE": "", "PMI_RANK": "0"}, (1, 0, None)),
    ({"PMI_SIZE": "two"}, (1, 0, None)),
    ({"PMI_SIZE": "2"}, (2, 0, "PMI_SIZE")),                  # no rank said: the first
], ids=["none", "pmi", "openmpi", "mvapich", "srun", "slurm-batch", "slurm-allocation",
        "mpiexec-n-1", "empty", "not-a-number", "no-rank"])
def test_launched_reads_the_launchers_variables(environ, expected):
    assert launched(environ) == expected


def test_launched_reads_this_processes_environment(monkeypatch):
    for pair in parallel.LAUNCHER_VARIABLES:
        for name in pair:
            monkeypatch.delenv(name, raising=False)
    assert launched() == (1, 0, None)
    monkeypatch.setenv("OMPI_COMM_WORLD_SIZE", "6")
    monkeypatch.setenv("OMPI_COMM_WORLD_RANK", "4")
    assert launched() == (6, 4, "OMPI_COMM_WORLD_SIZE")


# -- partition() ------------------------------------------------------------------------------

def test_partition_shares_the_chunks_evenly_the_first_processes_one_more():
    assert partition(24, 2, 5, 2) == [(0, 6), (6, 12), (12, 16), (16, 20), (20, 24)]
    assert partition(24, 8, 3, 2) == [(0, 8), (8, 16), (16, 24)]
    assert partition(7, 7, 1, 3) == [(0, 7)]
    for cells in range(3, 41):
        for chunk in [c for c in range(1, cells + 1) if cells % c == 0]:
            for processes in range(1, cells // chunk + 1):
                ranges = partition(cells, chunk, processes, 1)
                counts = [b - a for a, b in ranges]
                assert len(ranges) == processes and ranges[0][0] == 0
                assert ranges[-1][1] == cells
                assert all(a == b for (_, a), (b, _) in zip(ranges, ranges[1:]))  # contiguous
                assert all(c > 0 and c % chunk == 0 for c in counts)              # whole chunks
                assert max(counts) - min(counts) <= chunk                         # balanced
                assert counts == sorted(counts, reverse=True)             # the first ones more


def test_partition_takes_explicit_counts():
    assert partition(24, 2, 3, 2, [2, 16, 6]) == [(0, 2), (2, 18), (18, 24)]
    assert partition(24, 1, 2, 3, (3, 21)) == [(0, 3), (3, 24)]
    assert partition(24, 4, 2, 2, [numpy.int64(20), 4]) == [(0, 20), (20, 24)]


@pytest.mark.parametrize("arguments, parameter, words", [
    ((3, 1, 4, 1), "processes", "at most space.cells = 3"),
    ((24, 12, 3, 2), "processes", "at most the 2 chunks of space.block_cells = 12"),
    ((24, 2, 2, 2, [12, 12, 0]), "partition", "each of the 2 processes"),
    ((24, 2, 2, 2, [12]), "partition", "each of the 2 processes"),
    ((24, 2, 2, 2, [12, 10]), "partition", "adding up to space.cells = 24"),
    ((24, 4, 2, 2, [10, 14]), "partition", "multiples of space.block_cells = 4"),
    ((24, 2, 2, 2, [26, -2]), "partition", "multiples of space.block_cells"),
    ((24, 2, 2, 2, [12.5, 11.5]), "partition", "multiples of space.block_cells"),
    ((24, 2, 2, 2, ["12", 12]), "partition", "multiples of space.block_cells"),
    # chunks of one cell, MUSCL's ghost width 2: a block smaller than the stencil
    ((24, 1, 3, 2, [1, 12, 11]), "partition", "at least 2 cells, the reconstruction's ghost"),
    ((24, 1, 2, 3, [22, 2]), "partition", "at least 3 cells"),
], ids=["more-processes-than-cells", "more-processes-than-chunks", "zero-count",
        "too-few-counts", "wrong-sum", "partial-chunks", "negative", "fractional", "text",
        "below-the-ghost-width", "below-weno5s-ghost-width"])
def test_partition_refuses_what_processes_cannot_own(arguments, parameter, words):
    with pytest.raises(ValueError, match=f"partition: parameter '{parameter}'") as caught:
        partition(*arguments)
    assert words in str(caught.value)


# -- SerialCommunicator ------------------------------------------------------------------------

def test_the_serial_communicator_is_one_process():
    comm = SerialCommunicator()
    assert isinstance(comm, Communicator)
    assert (comm.rank, comm.size, comm.local_rank) == (0, 1, 0)
    gathered = comm.allgather([1, 2.5, 3])
    assert gathered.shape == (1, 3) and gathered.dtype == float
    numpy.testing.assert_array_equal(gathered, [[1.0, 2.5, 3.0]])
    value = {"a": [1, 2]}
    assert comm.allgather_object(value) == [value]
    assert comm.bcast(value) is value and comm.bcast(3, root=0) == 3
    assert repr(comm) == "SerialCommunicator()"
    with pytest.raises(SystemExit) as caught:
        comm.abort(4)
    assert caught.value.code == 4


def test_the_serial_communicator_delivers_messages_to_itself_by_tag():
    comm = SerialCommunicator()
    first, second = numpy.arange(6.0).reshape(2, 3), -numpy.arange(6.0).reshape(2, 3)
    into_first, into_second = numpy.zeros((2, 3)), numpy.zeros((2, 3))
    pending = comm.start([(0, 7, first), (0, 9, second)],
                         [(0, 9, into_second), (0, 7, into_first)])     # the other order
    assert isinstance(pending, Pending)
    first[...] = 99.0                      # the message was taken when posted
    pending.wait()
    numpy.testing.assert_array_equal(into_first, numpy.arange(6.0).reshape(2, 3))
    numpy.testing.assert_array_equal(into_second, -numpy.arange(6.0).reshape(2, 3))
    comm.start([], []).wait()


@pytest.mark.parametrize("sends, receives", [
    ([(0, 1, numpy.ones(2))], [(0, 2, numpy.zeros(2))]),         # no send of that tag
    ([(0, 1, numpy.ones(2))], [(1, 1, numpy.zeros(2))]),         # from a process not there
    ([], [(0, 0, numpy.zeros(2))]),
])
def test_the_serial_communicator_refuses_a_receive_nothing_sends(sends, receives):
    with pytest.raises(ValueError, match="parameter 'receives'.*must match a send"):
        SerialCommunicator().start(sends, receives)


def test_the_conformance_kit_passes_the_serial_communicator_and_catches_broken_ones():
    kit.check_communicator(SerialCommunicator())

    class InOrder(SerialCommunicator):
        """Matches receives to sends by their order, not their tags."""

        def start(self, sends, receives):
            for (_, _, array), (_, _, into) in zip(sends, receives):
                into[...] = array
            return parallel._Done()

    class Flat(SerialCommunicator):
        """Gathers a flat vector, not one row per process."""

        def allgather(self, vector):
            return numpy.asarray(vector, dtype=float)

    class Elsewhere(SerialCommunicator):
        rank = 1

    for broken, words in ((InOrder, "tag"), (Flat, "allgather"), (Elsewhere, "rank")):
        with pytest.raises(AssertionError, match=words):
            kit.check_communicator(broken())


# -- the halo: ghost cells through a communicator ------------------------------------------------

GRID = gf.VelocityGrid(dimension=2, n_modes=8, support_radius=3.0)
CELLS, BLOCK = 24, 4


def _f(seed=0):
    rng = numpy.random.default_rng(seed)
    x = (numpy.arange(CELLS) + 0.5) / CELLS
    rho = 1.0 + 0.3 * numpy.sin(2 * numpy.pi * x) + 0.05 * rng.random(CELLS)
    return rho[:, None, None] * GRID.maxwellian(temperature=0.8)[None] * (
        1.0 + 0.01 * rng.random((CELLS,) + GRID.shape))


class PostOffice:
    """The messages between the threads of :class:`ThreadCommunicator`, by (source,
    destination, tag)."""

    def __init__(self):
        self.letters, self.log = {}, []
        self.changed = threading.Condition()

    def post(self, source, destination, tag, array):
        with self.changed:
            key = (source, destination, tag)
            assert key not in self.letters, f"two messages in flight for {key}"
            self.letters[key] = numpy.array(array, copy=True)
            self.log.append(key + (array.shape,))
            self.changed.notify_all()

    def take(self, source, destination, tag):
        key = (source, destination, tag)
        with self.changed:
            assert self.changed.wait_for(lambda: key in self.letters, timeout=20), (
                f"no message {key} came")
            return self.letters.pop(key)


class ThreadCommunicator(Communicator):
    """Process ``rank`` of ``size`` as a thread: point-to-point messages through a
    :class:`PostOffice`, matched by (peer, tag) as MPI matches them."""

    def __init__(self, rank, size, office):
        self.rank, self.size, self.office = rank, size, office

    def start(self, sends, receives):
        assert all(array.flags.c_contiguous for _, _, array in sends + receives), (
            "the halo posts contiguous arrays")
        for peer, tag, array in sends:
            self.office.post(self.rank, peer, tag, array)
        office, rank = self.office, self.rank

        class Delivery(Pending):
            def wait(self):
                for peer, tag, array in receives:
                    letter = office.take(peer, rank, tag)
                    assert letter.shape == array.shape, (letter.shape, array.shape)
                    array[...] = letter

        return Delivery()

    def allgather(self, vector):
        raise NotImplementedError

    def allgather_object(self, value):
        raise NotImplementedError

    def bcast(self, value, root=0):
        raise NotImplementedError


def _in_threads(function, count):
    """``function(rank)`` for every rank at once, each in its own thread; their values."""
    values, errors = [None] * count, []

    def target(rank):
        try:
            values[rank] = function(rank)
        except BaseException as exc:        # reported below, in the test's thread
            errors.append(exc)

    threads = [threading.Thread(target=target, args=(rank,)) for rank in range(count)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join(60)
    if errors:
        raise errors[0]
    return values


@pytest.mark.parametrize("ends", ["periodic", "walls"])
@pytest.mark.parametrize("counts", [[8, 8, 8], [4, 12, 8]], ids=["even", "uneven"])
def test_three_domains_exchange_the_ghost_cells_of_one_owning_every_cell(ends, counts):
    """Three domains (threads) exchange their ends' ghost cells through a communicator
    that matches messages by (peer, tag): every block array, ghosts included, is the
    matching part of that of one domain owning every cell, bit for bit; each interior end
    sends one message of the ghost width, a wall end none."""
    left, right = ((Periodic(), Periodic()) if ends == "periodic" else
                   (Diffuse(temperature=1.2, accommodation=0.6), Specular()))
    ghost = WENO5.ghost
    ranges = partition(CELLS, BLOCK, 3, ghost, counts)
    whole = Domain(CELLS, 1.0, BLOCK, ghost, GRID)
    everything = whole.from_cells(_f())
    whole.exchange(everything, left, right, 0.25)
    office = PostOffice()

    def exchange(rank):
        communicator = ThreadCommunicator(rank, 3, office)
        domain = Domain(CELLS, 1.0, BLOCK, ghost, GRID, owned=ranges[rank])
        domain.neighbours = Halo.of(communicator, ranges, left.periodic)
        array = domain.from_cells(_f()[domain.owned])
        domain.exchange(array, left, right, 0.25)
        assert domain.neighbours.exchanges == 1 and domain.neighbours.seconds >= 0.0
        return domain, array

    for domain, array in _in_threads(exchange, 3):
        blocks = slice(domain.start // BLOCK, domain.stop // BLOCK)
        assert numpy.array_equal(array, everything[blocks]), (domain.start, domain.stop)
    assert not office.letters                           # every message received
    expected = 6 if ends == "periodic" else 4
    assert len(office.log) == expected
    assert all(shape == (ghost,) + GRID.shape for *_, shape in office.log)
    tags = {(source, destination): [] for source, destination, *_ in office.log}
    for source, destination, tag, _ in office.log:
        tags[(source, destination)].append(tag)
    assert tags[(0, 1)] == [RIGHTWARD] and tags[(1, 0)] == [LEFTWARD]
    if ends == "periodic":
        assert tags[(0, 2)] == [LEFTWARD] and tags[(2, 0)] == [RIGHTWARD]


def test_two_periodic_domains_are_each_others_neighbours_on_both_sides():
    """With two processes and periodic ends both neighbours are the same process: the
    two messages between them are told apart by their tags."""
    ghost = 2
    ranges = partition(CELLS, BLOCK, 2, ghost)
    whole = Domain(CELLS, 1.0, BLOCK, ghost, GRID)
    everything = whole.from_cells(_f(3))
    whole.exchange(everything, Periodic(), Periodic())
    office = PostOffice()

    def exchange(rank):
        communicator = ThreadCommunicator(rank, 2, office)
        domain = Domain(CELLS, 1.0, BLOCK, ghost, GRID, owned=ranges[rank])
        domain.neighbours = Halo.of(communicator, ranges, True)
        assert (domain.neighbours.left, domain.neighbours.right) == (1 - rank, 1 - rank)
        array = domain.from_cells(_f(3)[domain.owned])
        domain.exchange(array, Periodic(), Periodic())
        return domain, array

    for domain, array in _in_threads(exchange, 2):
        assert numpy.array_equal(array, everything[domain.start // BLOCK:domain.stop // BLOCK])


def test_the_halo_knows_its_neighbours_and_posts_only_the_sides_asked():
    serial = SerialCommunicator()
    for rank, size, periodic, expected in ((0, 3, False, (None, 1)), (2, 3, False, (1, None)),
                                           (1, 3, False, (0, 2)), (0, 3, True, (2, 1)),
                                           (2, 3, True, (1, 0))):
        serial.rank, serial.size = rank, size
        halo = Halo.of(serial, None, periodic)
        assert (halo.left, halo.right) == expected

    class Recorder(SerialCommunicator):
        def start(self, sends, receives):
            self.sends, self.receives = sends, receives
            return parallel._Done()

    domain = Domain(CELLS, 1.0, BLOCK, 2, GRID, owned=(8, 16))
    array = domain.from_cells(_f()[8:16])
    recorder = Recorder()
    halo = Halo(recorder, 0, 2)
    halo.start(domain, array, ("right",)).wait()
    assert [(peer, tag) for peer, tag, _ in recorder.sends] == [(2, RIGHTWARD)]
    assert [(peer, tag) for peer, tag, _ in recorder.receives] == [(2, LEFTWARD)]
    sent, into = recorder.sends[0][2], recorder.receives[0][2]
    assert numpy.shares_memory(sent, array) and numpy.shares_memory(into, array)
    numpy.testing.assert_array_equal(sent, _f()[14:16])          # the last 2 owned cells
    assert halo.exchanges == 1


# -- no MPI unless launched ---------------------------------------------------------------------

SPACE = """
final_time = 0.01
time_step = 0.002
[grid]
dimension = 2
n_modes = 16
support_radius = 3.2
[kernel]
name = "maxwell"
[restitution]
name = "constant"
value = 0.9
[initial]
name = "maxwellian"
[operator]
name = "fast_spectral"
[backend]
name = "numpy"
threads = 1
[space]
cells = 12
"""


def test_a_serial_space_run_never_imports_mpi4py():
    script = textwrap.dedent(f"""
        import sys
        import granframe
        from granframe.parallel import SerialCommunicator, world
        from granframe.registry import default_registries
        from granframe.run.description import RunDescription
        from granframe.run.problems.space import SpaceProblem
        assert "mpi" in default_registries().names("communicators")   # the plugin is there
        problem = SpaceProblem(RunDescription.from_toml({SPACE!r}))
        assert isinstance(problem.communicator, SerialCommunicator), problem.communicator
        assert problem.ranges == [(0, 12)] and isinstance(world(), SerialCommunicator)
        assert "mpi4py" not in sys.modules, "mpi4py imported"
        """)
    environ = {k: v for k, v in os.environ.items()
               if k not in {n for pair in parallel.LAUNCHER_VARIABLES for n in pair}}
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                          timeout=120, env=environ)
    assert done.returncode == 0, done.stderr


@pytest.fixture
def launched_as_rank_1_of_2(monkeypatch):
    """This process as rank 1 of 2 by Hydra's variables, with no communicator made yet."""
    for pair in parallel.LAUNCHER_VARIABLES:
        for name in pair:
            monkeypatch.delenv(name, raising=False)
    monkeypatch.setenv("PMI_SIZE", "2")
    monkeypatch.setenv("PMI_RANK", "1")
    monkeypatch.setattr(parallel, "_WORLD", [])


def test_world_without_the_mpi_plugin_says_what_to_install(launched_as_rank_1_of_2,
                                                           monkeypatch):
    import granframe.registry

    class WithoutMPI:
        def names(self, family):
            assert family == "communicators"
            return ["serial"]

        def create(self, family, name, **params):
            raise AssertionError("nothing to create")

    monkeypatch.setattr(granframe.registry, "default_registries", WithoutMPI)
    with pytest.raises(ValueError) as caught:
        world()
    message = str(caught.value)
    assert "rank 1 of 2 (PMI_SIZE = 2)" in message
    assert "no MPI communicator is installed" in message and "granframe[mpi]" in message
    assert parallel._WORLD == []                    # nothing kept: it fails again


def test_world_refuses_an_mpi_that_sees_fewer_processes_than_the_launcher(
        launched_as_rank_1_of_2):
    """PMI_SIZE = 2 in a plain process: MPI initialises alone (a singleton of one process),
    as when mpi4py is built against another MPI than the mpiexec that launched it."""
    pytest.importorskip("mpi4py")
    with pytest.raises(ValueError, match=r"started 2 processes \(PMI_SIZE\) but MPI sees 1: "
                                         r"mpiexec and mpi4py belong to different MPI"):
        world()
    assert parallel._WORLD == []


def test_world_is_made_once(monkeypatch):
    for pair in parallel.LAUNCHER_VARIABLES:
        for name in pair:
            monkeypatch.delenv(name, raising=False)
    monkeypatch.setattr(parallel, "_WORLD", [])
    first = world()
    assert isinstance(first, SerialCommunicator) and world() is first


# -- an error in one process of several ----------------------------------------------------------

class Aborting(SerialCommunicator):
    """Rank 1 of 2 whose abort returns (as MPICH's MPI_Abort can, under Hydra, before the
    launcher kills the process)."""

    rank, size = 1, 2

    def __init__(self):
        self.codes = []

    def abort(self, code):
        self.codes.append(code)


@pytest.mark.parametrize("error, code", [(ValueError("bad"), 2), (OSError("disk"), 2),
                                         (RuntimeError("bug"), 1)])
def test_an_error_in_one_process_aborts_them_all_and_never_goes_on(error, code, capfd):
    """granframe.tools.cli_run.together: the error is printed with the process's number and
    ends every process (abort with status 2 for granframe's refusals, 1 otherwise); the
    run does not carry on past it even where abort returns."""
    from granframe.tools.cli_run import together as _together

    communicator, went_on = Aborting(), []
    with pytest.raises(BaseException):
        with _together(communicator):
            raise error
        went_on.append(True)
    assert communicator.codes == [code] and not went_on
    assert f"granframe: error in process 1 of 2: {type(error).__name__}: {error}" in (
        capfd.readouterr().err)


def test_health_stops_and_interrupts_pass_through_together():
    from granframe.run.runner import HealthError
    from granframe.tools.cli_run import together as _together

    for error in (HealthError("stopped"), KeyboardInterrupt()):
        communicator = Aborting()
        with pytest.raises(type(error)):
            with _together(communicator):
                raise error
        assert communicator.codes == []
    with pytest.raises(ValueError):                          # one process: as it is
        with _together(SerialCommunicator()):
            raise ValueError("alone")
