"""GPIO backends for the record button and its LED.

- :class:`JetsonGpio`  the Orin's pins through NVIDIA's Jetson.GPIO (only importable on a Jetson)
- :class:`FileGpio`    each pin is a file holding "0" or "1" in a folder: a test (or a person with a shell)
                       presses the button of a running service from another process, and reads its LED
- :class:`MemoryGpio`  pins in memory, for tests that drive the state machine in-process

All three poll: the button is sampled by the service loop and debounced in software (button.py),
so every backend behaves the same.
"""
from __future__ import annotations

import os
from pathlib import Path
from typing import Protocol


class GpioError(Exception):
    """A pin cannot be used; the message names the backend and the pin."""


class Gpio(Protocol):
    def setup_input(self, pin: int) -> None: ...
    def setup_output(self, pin: int) -> None: ...
    def read(self, pin: int) -> int: ...
    def write(self, pin: int, value: int) -> None: ...
    def close(self) -> None: ...


class MemoryGpio:
    def __init__(self, idle_level: int = 1):
        self.levels: dict[int, int] = {}
        self.idle_level = idle_level
        self.writes: list[tuple[int, int]] = []

    def setup_input(self, pin: int) -> None:
        self.levels.setdefault(pin, self.idle_level)

    def setup_output(self, pin: int) -> None:
        self.levels.setdefault(pin, 0)

    def read(self, pin: int) -> int:
        return self.levels[pin]

    def write(self, pin: int, value: int) -> None:
        self.levels[pin] = int(value)
        self.writes.append((pin, int(value)))

    def close(self) -> None:
        pass


class FileGpio:
    """Pins as files ``<folder>/pin<N>``. An input pin file is created at its idle level."""

    def __init__(self, folder: Path | str, idle_level: int = 1):
        self.folder = Path(folder)
        self.idle_level = idle_level
        try:
            self.folder.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise GpioError(f"file GPIO {self.folder}: cannot create the folder ({exc.strerror})") from None

    def path(self, pin: int) -> Path:
        return self.folder / f"pin{pin}"

    def _put(self, pin: int, value: int) -> None:
        tmp = self.folder / f".pin{pin}.tmp"
        tmp.write_text(f"{int(value)}\n")
        os.replace(tmp, self.path(pin))

    def setup_input(self, pin: int) -> None:
        if not self.path(pin).exists():
            self._put(pin, self.idle_level)

    def setup_output(self, pin: int) -> None:
        self._put(pin, 0)

    def read(self, pin: int) -> int:
        try:
            return 1 if self.path(pin).read_text().strip() == "1" else 0
        except FileNotFoundError:
            return self.idle_level

    def write(self, pin: int, value: int) -> None:
        self._put(pin, value)

    def close(self) -> None:
        pass


class JetsonGpio:
    """Jetson.GPIO with the rig's pin numbering. Inside Docker it needs the gpiochip devices and,
    when not privileged, JETSON_MODEL_NAME (the compose file sets both)."""

    def __init__(self, numbering: str):
        try:
            import Jetson.GPIO as GPIO  # noqa: N814  (NVIDIA's module name)
        except ImportError:
            raise GpioError("Jetson.GPIO is not importable: on the Orin install it (pip install Jetson.GPIO); "
                            "elsewhere use --gpio file:DIR") from None
        except RuntimeError as exc:  # raised when the board is not recognised
            raise GpioError(f"Jetson.GPIO: {exc}") from None
        self.GPIO = GPIO
        GPIO.setwarnings(False)
        GPIO.setmode(getattr(GPIO, numbering))

    def setup_input(self, pin: int) -> None:
        self.GPIO.setup(pin, self.GPIO.IN)

    def setup_output(self, pin: int) -> None:
        self.GPIO.setup(pin, self.GPIO.OUT, initial=self.GPIO.LOW)

    def read(self, pin: int) -> int:
        return int(self.GPIO.input(pin))

    def write(self, pin: int, value: int) -> None:
        self.GPIO.output(pin, self.GPIO.HIGH if value else self.GPIO.LOW)

    def close(self) -> None:
        self.GPIO.cleanup()


def open_gpio(spec: str, numbering: str, idle_level: int) -> Gpio:
    """``jetson`` or ``file:DIR`` (the --gpio option of record-service)."""
    if spec == "jetson":
        return JetsonGpio(numbering)
    if spec.startswith("file:") and len(spec) > 5:
        return FileGpio(spec[5:], idle_level)
    raise GpioError(f"--gpio {spec}: expected 'jetson' or 'file:DIR'")
