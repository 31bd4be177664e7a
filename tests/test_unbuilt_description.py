"""Descriptions are checked without building their operator or backend; a run builds each
component once; reading a store (info, plot, xarray) never builds its backend."""

import pytest
import xarray

import granframe_cupy
from granframe.registry import Registries
from granframe.run.description import RunDescription
from granframe.run.runner import Simulation
from granframe.run.storage import RunStore
from granframe.tools.cli import main

from test_runner import heated


def _refuse_building_cupy(monkeypatch):
    """Make any construction or import of the CuPy backend fail the test."""
    def refuse(*args, **kwargs):
        raise AssertionError("the CuPy backend was built or imported")
    monkeypatch.setattr(granframe_cupy.CuPyBackend, "__attrs_post_init__", refuse)
    monkeypatch.setattr(granframe_cupy, "_import", refuse)


def write_gpu_store(path) -> dict:
    """A store as a GPU run leaves it for a CPU machine: written by the CuPy backend's host
    path, its description (table and TOML) then made the GPU one's. Returns its metadata."""
    Simulation(heated(final_time=0.5, backend={"name": "cupy", "module": "numpy"})).run(
        path, progress=False)
    written = RunStore.open(path, mode="r+")
    meta = written.metadata
    meta["description"]["backend"] = {"name": "cupy"}
    meta["description_toml"] = RunDescription.from_dict(meta["description"]).to_toml()
    written.group.attrs.update({"granframe": meta, "description_toml": meta["description_toml"]})
    return meta


def test_a_cupy_store_is_read_without_building_its_backend(tmp_path, capsys, monkeypatch):
    store = tmp_path / "gpu.zarr"
    meta = write_gpu_store(store)
    _refuse_building_cupy(monkeypatch)
    description = RunDescription.from_dict(meta["description"])
    assert description.backend.name == "cupy"
    for command in (["info", str(store)], ["plot", str(store), "--out", str(tmp_path / "fig")]):
        assert main(command) == 0, capsys.readouterr().err
    assert (tmp_path / "fig" / "temperature.png").is_file()
    with xarray.open_zarr(store, consolidated=False) as data:
        assert data["f"].shape[0] == RunStore.open(store).snapshot_count


def test_backend_parameters_are_checked_without_building_it(monkeypatch):
    _refuse_building_cupy(monkeypatch)
    assert heated(backend={"name": "cupy", "device": 3}).backend.params == {"device": 3}
    with pytest.raises(ValueError, match="CuPyBackend: parameter 'module' = 'torch'"):
        heated(backend={"name": "cupy", "module": "torch"})
    with pytest.raises(ValueError, match="CuPyBackend: parameter 'device' = -1"):
        heated(backend={"name": "cupy", "device": -1})
    with pytest.raises(TypeError, match="array_backends 'cupy': unknown parameter 'devices'; "
                                        "did you mean 'device'\\? Accepted parameters: device"):
        heated(backend={"name": "cupy", "devices": 1})


def test_a_simulation_builds_each_component_once(monkeypatch):
    description = heated()
    built = []
    create = Registries.create

    def counting(self, family, name, **params):
        built.append(family)
        return create(self, family, name, **params)

    monkeypatch.setattr(Registries, "create", counting)
    Simulation(description)
    assert sorted(built) == ["array_backends", "collision_operators"]  # the rest: validated
    assert description.build("kernel") is description.build("kernel")
