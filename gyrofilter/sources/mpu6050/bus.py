"""The I2C bus of an MPU-6050 as the user names it: a bus number ``N`` (``/dev/i2c-N``), a device
path or an smbus2-like object, opened with smbus2 (imported only here, when a bus is opened) with
the operating system's refusals turned into one-line errors that say what to do; and the whole
numbers a user gives for an address or a setting (:func:`as_int`)."""
from ...errors import DeviceError, SettingsError

__all__ = ["as_int", "bus_name", "bus_number", "open_bus"]


def as_int(value, name):
    """``value`` as an int: an int, or text of a Python integer literal in ASCII (``0x68``, ``104``;
    no other script's digits, as every number a user gives: :mod:`gyrofilter.inputs`)."""
    try:
        if isinstance(value, str) and not value.isascii():
            raise ValueError(value)
        return int(value, 0) if isinstance(value, str) else int(value)
    except (TypeError, ValueError):
        raise SettingsError(f"{name}={value!r} is not an integer") from None


def bus_name(bus):
    """The bus as messages name it: ``/dev/i2c-N`` for a number, a path as given, else its repr."""
    if isinstance(bus, int):
        return f"/dev/i2c-{bus}"
    if isinstance(bus, str):
        return bus
    return repr(bus)


def bus_number(bus):
    """N of ``/dev/i2c-N`` (for the ``i2cdetect -y N`` of a hint); 1, the Pi's bus, when unknown."""
    if isinstance(bus, int):
        return bus
    if isinstance(bus, str) and bus.startswith("/dev/i2c-") and bus[9:].isdigit():
        return int(bus[9:])
    return 1


def open_bus(bus):
    """Open ``/dev/i2c-N`` with smbus2; turn the OS errors into one-line errors with a hint."""
    import smbus2  # imported only when a device is opened

    name = bus_name(bus)
    try:
        return smbus2.SMBus(bus)
    except FileNotFoundError:
        raise DeviceError(
            f"no I2C bus {name}: enable I2C (sudo raspi-config -> Interface Options -> I2C, or "
            f"dtparam=i2c_arm=on in /boot/firmware/config.txt) and reboot; `ls /dev/i2c-*` lists the buses") from None
    except PermissionError:
        raise DeviceError(
            f"permission denied opening {name}: add your user to the i2c group "
            f"(sudo adduser $USER i2c, then log out and in) or check the device's permissions") from None
    except OSError as exc:
        raise DeviceError(f"cannot open I2C bus {name}: {exc.strerror or exc} (errno {exc.errno})") from None
