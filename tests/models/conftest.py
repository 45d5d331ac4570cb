"""Fixtures for the model FMU tests: FMUs built once per session into a tmp dir, and a
small wrapper around fmpy's FMU2Slave that captures the FMU's log messages."""

from __future__ import annotations

import ctypes
from pathlib import Path

import pytest
from fmpy import extract, read_model_description
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import (
    FMU2Slave,
    defaultCallbacks,
    fmi2CallbackFunctions,
    fmi2CallbackLoggerTYPE,
)
from fmpy.logging import addLoggerProxy

from orchestrator import fmu_build


@pytest.fixture(scope="session")
def fmus(tmp_path_factory) -> dict[str, Path]:
    """Every model built from the repository's sources into a session tmp dir."""
    out_dir = tmp_path_factory.mktemp("fmus")
    return {p.stem: p for p in fmu_build.build_all(out_dir)}


class Slave:
    """An instantiated FMU2Slave with value references by name and captured log messages."""

    def __init__(self, fmu: Path, unzip_dir: Path, instance_name: str = "test"):
        self.description = read_model_description(str(fmu))
        self.vr = {v.name: v.valueReference for v in self.description.modelVariables}
        self.messages: list[tuple[int, str]] = []

        def logger(component, name, status, category, message):
            self.messages.append((status, message.decode("utf-8", "replace")))

        self._logger = fmi2CallbackLoggerTYPE(logger)  # keep a reference alive
        self._callbacks = fmi2CallbackFunctions()
        self._callbacks.logger = self._logger
        self._callbacks.allocateMemory = defaultCallbacks.allocateMemory
        self._callbacks.freeMemory = defaultCallbacks.freeMemory
        addLoggerProxy(ctypes.byref(self._callbacks))
        self.fmu = FMU2Slave(
            guid=self.description.guid,
            unzipDirectory=str(extract(str(fmu), str(unzip_dir))),
            modelIdentifier=self.description.coSimulation.modelIdentifier,
            instanceName=instance_name,
        )
        self.fmu.instantiate(callbacks=self._callbacks)

    def initialize(self, start_values: dict[str, float | str] | None = None,
                   start_time: float = 0.0) -> None:
        self.fmu.setupExperiment(startTime=start_time)
        self.fmu.enterInitializationMode()
        self.set(start_values or {})
        self.fmu.exitInitializationMode()

    def set(self, values: dict[str, float | str]) -> None:
        for name, value in values.items():
            if isinstance(value, str):
                self.fmu.setString([self.vr[name]], [value])
            else:
                self.fmu.setReal([self.vr[name]], [float(value)])

    def get(self, *names: str) -> list[float]:
        return self.fmu.getReal([self.vr[n] for n in names])

    def errors(self) -> str:
        return "\n".join(m for status, m in self.messages if status >= 3)

    def close(self) -> None:
        self.fmu.freeInstance()


@pytest.fixture
def slave_class():
    """:class:`Slave` itself, for a test that chooses the folder the FMU is unpacked to (a
    fixture, because a test module cannot import this conftest by name when the other test
    folders' conftests are collected too)."""
    return Slave


@pytest.fixture
def open_slave(tmp_path):
    """Factory: open_slave(fmu_path) -> Slave, freed after the test."""
    opened: list[Slave] = []

    def factory(fmu: Path) -> Slave:
        slave = Slave(fmu, tmp_path / f"unzip{len(opened)}")
        opened.append(slave)
        return slave

    yield factory
    for slave in opened:
        slave.close()


@pytest.fixture
def refused_at_initialization(fmus, open_slave):
    """Check: refused_at_initialization(model, name, value, message): the model's FMU refuses
    ``name = value`` when it leaves initialization mode, with ``message`` in its log."""

    def check(model: str, name: str, value: float, message: str) -> None:
        ship = open_slave(fmus[model])
        ship.fmu.setupExperiment(startTime=0.0)
        ship.fmu.enterInitializationMode()
        ship.set({name: value})
        with pytest.raises(FMICallException):
            ship.fmu.exitInitializationMode()
        assert message in ship.errors()

    return check
