"""Simulated devices of the OP2 bus: a CM-740 sub-controller and MX-28 servos.

Each device holds a Protocol 1.0 control table (a bytearray) described by `Item`s. Reads of any
range inside the table succeed; writes are refused with a RANGE error when they touch a read-only
or unused byte, or put a value outside an item's range. An MX-28 moves its present position toward
its goal (first-order response with a speed limit) whenever its state is advanced to a time.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from services.motion.joints import CM740_ID, CM740_MODEL, MX28_MODEL
from services.motion.protocol import ErrorBit

MX28_MAX_SPEED = 55.0 * 4096 / 60.0
"""No-load speed at 12 V, ticks per second (55 rpm)."""
SPEED_UNIT = 0.114 * 4096 / 60.0
"""One unit of the moving-speed register (0.114 rpm) in ticks per second."""
RESPONSE_TIME_S = 0.02
"""First-order time constant of the position loop at P gain 32 (scales inversely with P)."""


@dataclass(frozen=True)
class Item:
    addr: int
    size: int
    name: str
    writable: bool
    default: int = 0
    lo: int = 0
    hi: int = 0xFFFF


class Device:
    """A control table with typed items; subclasses add behaviour."""

    ITEMS: tuple[Item, ...] = ()
    SIZE = 0

    def __init__(self, dev_id: int) -> None:
        self.table = bytearray(self.SIZE)
        self._items = {it.addr: it for it in self.ITEMS}
        self._writable = bytearray(self.SIZE)
        for it in self.ITEMS:
            self.set(it.name, it.default)
            if it.writable:
                self._writable[it.addr : it.addr + it.size] = b"\x01" * it.size
        self.set("id", dev_id)

    # -------------------------------------------------------------- register access
    def item(self, name: str) -> Item:
        for it in self.ITEMS:
            if it.name == name:
                return it
        raise KeyError(name)

    def get(self, name: str) -> int:
        it = self.item(name)
        return int.from_bytes(self.table[it.addr : it.addr + it.size], "little")

    def set(self, name: str, value: int) -> None:
        it = self.item(name)
        self.table[it.addr : it.addr + it.size] = int(value).to_bytes(it.size, "little")

    @property
    def id(self) -> int:
        return self.table[3]

    def read(self, addr: int, length: int) -> tuple[int, bytes]:
        """(error bits, data). A range outside the table is a RANGE error with no data."""
        if length < 1 or addr + length > self.SIZE:
            return ErrorBit.RANGE, b""
        return 0, bytes(self.table[addr : addr + length])

    def write(self, addr: int, data: bytes) -> int:
        """Write `data` at `addr`; returns error bits (0 when written)."""
        if not data or addr + len(data) > self.SIZE:
            return ErrorBit.RANGE
        if not all(self._writable[addr : addr + len(data)]):
            return ErrorBit.RANGE
        staged = bytearray(self.table)
        staged[addr : addr + len(data)] = data
        for it in self.ITEMS:
            if it.writable and it.addr < addr + len(data) and addr < it.addr + it.size:
                value = int.from_bytes(staged[it.addr : it.addr + it.size], "little")
                if not it.lo <= value <= it.hi:
                    return ErrorBit.RANGE
        error = self.check_write(staged, addr, len(data))
        if error & ErrorBit.RANGE:
            return error
        self.table[:] = staged
        self.after_write(addr, len(data))
        return error

    def check_write(self, staged: bytearray, addr: int, length: int) -> int:
        """Device-specific checks of a staged write; may adjust `staged`. Returns error bits."""
        return 0

    def after_write(self, addr: int, length: int) -> None:
        pass

    def advance(self, now: float) -> None:
        pass

    @property
    def status_return_level(self) -> int:
        return self.table[16]

    @property
    def return_delay_s(self) -> float:
        return self.table[5] * 2e-6


def _item(
    addr: int, size: int, name: str, rw: bool, default: int = 0, lo: int = 0, hi: int | None = None
) -> Item:
    return Item(addr, size, name, rw, default, lo, hi if hi is not None else (1 << (8 * size)) - 1)


class MX28(Device):
    """An MX-28 servo (Protocol 1.0 control table, firmware as shipped in an OP2)."""

    ITEMS = (
        _item(0, 2, "model_number", False, MX28_MODEL),
        _item(2, 1, "firmware", False, 30),
        _item(3, 1, "id", True, 1, 0, 253),
        _item(4, 1, "baud_rate", True, 1, 0, 254),
        _item(5, 1, "return_delay", True, 0, 0, 254),
        _item(6, 2, "cw_angle_limit", True, 0, 0, 4095),
        _item(8, 2, "ccw_angle_limit", True, 4095, 0, 4095),
        _item(11, 1, "temperature_limit", True, 80, 0, 99),
        _item(12, 1, "min_voltage", True, 60, 50, 160),
        _item(13, 1, "max_voltage", True, 160, 50, 160),
        _item(14, 2, "max_torque", True, 1023, 0, 1023),
        _item(16, 1, "status_return_level", True, 2, 0, 2),
        _item(17, 1, "alarm_led", True, 36, 0, 127),
        _item(18, 1, "shutdown", True, 36, 0, 127),
        _item(20, 2, "multi_turn_offset", True, 0),
        _item(22, 1, "resolution_divider", True, 1, 1, 4),
        _item(24, 1, "torque_enable", True, 0, 0, 1),
        _item(25, 1, "led", True, 0, 0, 1),
        _item(26, 1, "d_gain", True, 0, 0, 254),
        _item(27, 1, "i_gain", True, 0, 0, 254),
        _item(28, 1, "p_gain", True, 32, 0, 254),
        _item(29, 1, "reserved", True, 0),
        _item(30, 2, "goal_position", True, 2048, 0, 4095),
        _item(32, 2, "moving_speed", True, 0, 0, 1023),
        _item(34, 2, "torque_limit", True, 1023, 0, 1023),
        _item(36, 2, "present_position", False, 2048),
        _item(38, 2, "present_speed", False, 0),
        _item(40, 2, "present_load", False, 0),
        _item(42, 1, "present_voltage", False, 120),
        _item(43, 1, "present_temperature", False, 38),
        _item(44, 1, "registered", False, 0),
        _item(46, 1, "moving", False, 0),
        _item(47, 1, "lock", True, 0, 0, 1),
        _item(48, 2, "punch", True, 32, 0, 1023),
        _item(73, 1, "goal_acceleration", True, 0, 0, 254),
    )
    SIZE = 74

    def __init__(self, dev_id: int, position: int = 2048) -> None:
        super().__init__(dev_id)
        self.position = float(position)
        self._last: float | None = None
        self.reset_ram()

    def reset_ram(self) -> None:
        """Power-on state of the RAM area: torque off, goal = present position."""
        for name in ("torque_enable", "led", "d_gain", "i_gain", "present_speed", "present_load", "moving"):
            self.set(name, 0)
        self.set("p_gain", 32)
        self.set("torque_limit", self.get("max_torque"))
        self.set("present_position", round(self.position))
        self.set("goal_position", round(self.position))
        self._last = None

    def check_write(self, staged: bytearray, addr: int, length: int) -> int:
        if not (addr < 32 and addr + length > 30):
            return 0
        goal = int.from_bytes(staged[30:32], "little")
        cw = int.from_bytes(staged[6:8], "little")
        ccw = int.from_bytes(staged[8:10], "little")
        if (cw or ccw) and not cw <= goal <= ccw:
            staged[30:32] = min(max(goal, cw), ccw).to_bytes(2, "little")
            return ErrorBit.ANGLE
        return 0

    def advance(self, now: float) -> None:
        last, self._last = self._last, now
        if last is None or now <= last:
            return
        dt = now - last
        goal = self.get("goal_position")
        error = goal - self.position
        step = 0.0
        if self.table[24] and error:
            p_gain = max(self.table[28], 1)
            tau = RESPONSE_TIME_S * 32.0 / p_gain
            speed_reg = self.get("moving_speed")
            vmax = MX28_MAX_SPEED if speed_reg == 0 else min(speed_reg * SPEED_UNIT, MX28_MAX_SPEED)
            step = error * (1.0 - math.exp(-dt / tau))
            limit = vmax * dt
            step = max(-limit, min(limit, step))
            self.position += step
            if abs(goal - self.position) < 0.5:
                self.position = float(goal)
        velocity = step / dt
        speed_units = min(int(abs(velocity) / SPEED_UNIT), 1023)
        self.set("present_position", round(self.position))
        self.set("present_speed", speed_units | (1024 if velocity < 0 else 0))
        load = min(int(abs(goal - self.position) * 4), 1023) if self.table[24] else 0
        self.set("present_load", load | (1024 if goal < self.position else 0))
        self.set("moving", 1 if self.table[24] and abs(goal - self.position) >= 1 else 0)


class CM740(Device):
    """The OP2's sub-controller: powers the servo bus (address 24) and carries the IMU."""

    ITEMS = (
        _item(0, 2, "model_number", False, CM740_MODEL),
        _item(2, 1, "firmware", False, 0x0D),
        _item(3, 1, "id", True, CM740_ID, 0, 253),
        _item(4, 1, "baud_rate", True, 1, 0, 254),
        _item(5, 1, "return_delay", True, 0, 0, 254),
        _item(16, 1, "status_return_level", True, 2, 0, 2),
        _item(24, 1, "dynamixel_power", True, 0, 0, 1),
        _item(25, 1, "led_panel", True, 0, 0, 7),
        _item(26, 2, "led_head", True, 0, 0, 0x7FFF),
        _item(28, 2, "led_eye", True, 0, 0, 0x7FFF),
        _item(30, 1, "button", False, 0),
        _item(38, 2, "gyro_z", False, 512),
        _item(40, 2, "gyro_y", False, 512),
        _item(42, 2, "gyro_x", False, 512),
        _item(44, 2, "acc_x", False, 512),
        _item(46, 2, "acc_y", False, 512),
        _item(48, 2, "acc_z", False, 512),
        _item(50, 1, "voltage", False, 120),
    )
    SIZE = 51

    @property
    def power(self) -> bool:
        return bool(self.table[24])
