"""The OP2 bus through the real dynamixel-sdk (Protocol 1.0): power, joint check, SYNC_WRITE, BULK_READ.

Two small adaptations of the SDK, both in subclasses:
- `WaitingPortHandler` waits for reply bytes with select() instead of the SDK's busy polling (the
  SDK reads a non-blocking port in a tight loop), and makes the USB latency allowance of the
  packet timeout configurable (the SDK hard-codes 16 ms).
- `Op2BulkRead` fixes `GroupBulkRead.txPacket` for Protocol 1.0 (the SDK passes a Protocol 2.0
  argument and raises TypeError, REFERENCE.md) and records which device a failed read stopped at.
"""

from __future__ import annotations

import os
import select
import termios
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, TypeVar

import serial
from dynamixel_sdk import COMM_SUCCESS, GroupBulkRead, GroupSyncWrite, PacketHandler, PortHandler
from dynamixel_sdk.group_bulk_read import PARAM_NUM_DATA, PARAM_NUM_LENGTH
from dynamixel_sdk.robotis_def import COMM_RX_TIMEOUT

from services.motion.joints import CM740_ID, CM740_MODEL, JOINT_IDS, MX28_MODEL, describe

ADDR_TORQUE = 24
ADDR_GAINS = 26
ADDR_PRESENT_POSITION = 36
ADDR_CM740_POWER = 24
SYNC_LEN = 6  # D, I, P, reserved, goal low, goal high

PORT_ERRORS = (OSError, serial.SerialException, termios.error)
T = TypeVar("T")


class BusError(Exception):
    """The bus cannot be used; the message says why and what to do."""


class PortMissing(BusError):
    pass


class PortLost(BusError):
    pass


class NoAnswer(BusError):
    """The port is open but nothing answers (robot switched off, cable out)."""


class ReplyMismatch(BusError):
    """A status packet that did not fit the request (late reply of an earlier exchange)."""


class JointsMissing(BusError):
    def __init__(self, missing: list[int], wrong: dict[int, int], port: str) -> None:
        self.missing = missing
        self.wrong = wrong
        parts = []
        if missing:
            parts.append("no answer from " + ", ".join(describe(i) for i in missing))
        if wrong:
            parts.append(
                "wrong model at "
                + ", ".join(
                    f"{describe(i)}: model {m}, expected MX-28 ({MX28_MODEL})" for i, m in wrong.items()
                )
            )
        super().__init__(f"{'; '.join(parts)} on {port}")


class WaitingPortHandler(PortHandler):  # type: ignore[misc]
    def __init__(self, port_name: str, latency_ms: float = 16.0) -> None:
        super().__init__(port_name)
        self.latency_ms = latency_ms

    def setPacketTimeout(self, packet_length: int) -> None:
        self.packet_start_time = self.getCurrentTime()
        self.packet_timeout = self.tx_time_per_byte * packet_length + self.latency_ms * 2.0 + 2.0

    def readPort(self, length: int) -> bytes:
        remaining_ms = self.packet_timeout - self.getTimeSinceStart()
        if remaining_ms > 0 and not self.ser.in_waiting:
            select.select([self.ser.fileno()], [], [], remaining_ms / 1000.0)
        return bytes(self.ser.read(length))


class Op2BulkRead(GroupBulkRead):  # type: ignore[misc]
    failed_id: int | None = None

    def txPacket(self) -> int:
        if not self.data_dict:
            return -3001  # COMM_NOT_AVAILABLE
        if self.is_param_changed or not self.param:
            self.makeParam()
        return int(self.ph.bulkReadTx(self.port, self.param, len(self.data_dict) * 3))

    def rxPacket(self) -> int:
        self.last_result = False
        self.failed_id = None
        result = COMM_RX_TIMEOUT
        for dxl_id, entry in self.data_dict.items():
            entry[0], result, _ = self.ph.readRx(self.port, dxl_id, entry[2])
            if result != COMM_SUCCESS:
                self.failed_id = dxl_id
                return int(result)
        self.last_result = True
        return int(result)


@dataclass
class BusCounters:
    sync_writes: int = 0
    bulk_reads: int = 0
    read_failures: int = 0
    rx_timeouts: int = 0
    rx_corrupt: int = 0
    pings: int = 0

    def as_dict(self) -> dict[str, int]:
        return dict(self.__dict__)


@dataclass
class ReadResult:
    ok: bool
    positions: dict[int, int] = field(default_factory=dict)
    failed_id: int | None = None
    timeout: bool = False
    message: str = ""


class Op2Bus:
    """One open Dynamixel port with the OP2's devices on it. Not thread-safe: one thread uses it."""

    def __init__(self, port: str, *, baud: int = 1_000_000, latency_ms: float = 16.0) -> None:
        self.port_name = port
        self.baud = baud
        self.counters = BusCounters()
        self._port = WaitingPortHandler(port, latency_ms)
        self._ph = PacketHandler(1.0)
        self._sync = GroupSyncWrite(self._port, self._ph, ADDR_GAINS, SYNC_LEN)
        self._bulk = Op2BulkRead(self._port, self._ph)
        self._open = False

    # ------------------------------------------------------------------ set-up
    def open(self) -> None:
        if not os.path.exists(self.port_name):
            raise PortMissing(f"serial port {self.port_name} does not exist")
        self._port.baudrate = self.baud
        try:
            ok = self._port.openPort()
        except PORT_ERRORS as exc:
            raise PortMissing(f"cannot open {self.port_name}: {exc}") from None
        if not ok:
            raise BusError(f"cannot set {self.baud} bps on {self.port_name}")
        self._open = True

    def close(self) -> None:
        if self._open:
            self._open = False
            try:
                self._port.closePort()
            except PORT_ERRORS:
                pass

    def power_on(self, attempts: int = 3, settle_s: float = 0.1) -> None:
        """Switch the servo power on through the CM-740 (ID 200, address 24)."""
        model, result, _ = self._call(self._ph.ping, self._port, CM740_ID)
        for _ in range(attempts - 1):
            if result == COMM_SUCCESS:
                break
            self._discard_input()  # a late answer to the last ping must not pass for the next one
            model, result, _ = self._call(self._ph.ping, self._port, CM740_ID)
        if result != COMM_SUCCESS:
            raise NoAnswer(
                f"the CM-740 sub-controller (ID {CM740_ID}) does not answer on {self.port_name}: "
                f"{self._ph.getTxRxResult(result)} (is the robot switched on?)"
            )
        if model != CM740_MODEL:
            raise BusError(
                f"ID {CM740_ID} on {self.port_name} is model {model:#x}, not a CM-740 ({CM740_MODEL:#x})"
            )
        power, result, _ = self._call(self._ph.read1ByteTxRx, self._port, CM740_ID, ADDR_CM740_POWER)
        if result == COMM_SUCCESS and power == 1:
            return
        result, error = self._call(self._ph.write1ByteTxRx, self._port, CM740_ID, ADDR_CM740_POWER, 1)
        if result != COMM_SUCCESS or error:
            raise BusError(f"cannot power the servos through the CM-740: {self._ph.getTxRxResult(result)}")
        time.sleep(settle_s)

    def check_joints(self, retries: int = 2) -> None:
        """Ping all twenty joints and check their model; raises JointsMissing naming each bad one."""
        missing: list[int] = []
        wrong: dict[int, int] = {}
        for jid in JOINT_IDS:
            model = self.ping(jid, retries)
            if model is None:
                missing.append(jid)
            elif model != MX28_MODEL:
                wrong[jid] = model
        if missing or wrong:
            raise JointsMissing(missing, wrong, self.port_name)

    def ping(self, dev_id: int, retries: int = 1) -> int | None:
        """Model number, or None when the device does not answer."""
        for _ in range(retries + 1):
            self.counters.pings += 1
            try:
                model, result, _ = self._call(self._ph.ping, self._port, dev_id)
            except ReplyMismatch:
                continue
            if result == COMM_SUCCESS:
                return int(model)
        return None

    def read_positions(self, ids: tuple[int, ...] = JOINT_IDS) -> dict[int, int]:
        """Present positions one READ at a time (start-up, before the bulk read is trusted)."""
        out: dict[int, int] = {}
        for jid in ids:
            value, result, _ = self._call(self._ph.read2ByteTxRx, self._port, jid, ADDR_PRESENT_POSITION)
            if result != COMM_SUCCESS:
                value, result, _ = self._call(self._ph.read2ByteTxRx, self._port, jid, ADDR_PRESENT_POSITION)
            if result != COMM_SUCCESS:
                raise BusError(
                    f"cannot read the position of {describe(jid)}: {self._ph.getTxRxResult(result)}"
                )
            out[jid] = int(value)
        return out

    def set_torque(self, on: bool, ids: tuple[int, ...] = JOINT_IDS) -> None:
        """Torque on/off for `ids` in one SYNC_WRITE."""
        group = GroupSyncWrite(self._port, self._ph, ADDR_TORQUE, 1)
        for jid in ids:
            group.addParam(jid, [1 if on else 0])
        result = self._call(group.txPacket)
        if result != COMM_SUCCESS:
            raise BusError(f"torque {'on' if on else 'off'} failed: {self._ph.getTxRxResult(result)}")

    def set_bulk_ids(self, ids: list[int]) -> None:
        """The joints read by every BULK_READ (present position), in this order."""
        self._bulk.clearParam()
        self._bulk.is_param_changed = True
        for jid in ids:
            self._bulk.addParam(jid, ADDR_PRESENT_POSITION, 2)

    # ------------------------------------------------------------------ per tick
    def write_goals(self, goals: dict[int, int], gains: dict[int, tuple[int, int, int]]) -> float:
        """One SYNC_WRITE of gains and goal positions for every joint; returns time.time() of the write."""
        for jid, goal in goals.items():
            d, i, p = gains[jid]
            data = [d, i, p, 0, goal & 0xFF, (goal >> 8) & 0xFF]
            if not self._sync.changeParam(jid, data):
                self._sync.addParam(jid, data)
        when = time.time()
        result = self._call(self._sync.txPacket)
        if result != COMM_SUCCESS:
            raise PortLost(f"SYNC_WRITE failed on {self.port_name}: {self._ph.getTxRxResult(result)}")
        self.counters.sync_writes += 1
        return when

    def bulk_read(self) -> ReadResult:
        """One BULK_READ of the present positions of the configured joints."""
        if not self._bulk.data_dict:
            return ReadResult(ok=True)
        self.counters.bulk_reads += 1
        result = self._call(self._bulk.txPacket)
        if result != COMM_SUCCESS:
            raise PortLost(
                f"BULK_READ could not be sent on {self.port_name}: {self._ph.getTxRxResult(result)}"
            )
        result = self._call(self._bulk.rxPacket)
        if result != COMM_SUCCESS:
            self.counters.read_failures += 1
            timeout = result == COMM_RX_TIMEOUT
            if timeout:
                self.counters.rx_timeouts += 1
            else:
                self.counters.rx_corrupt += 1
            return ReadResult(
                ok=False,
                failed_id=self._bulk.failed_id,
                timeout=timeout,
                message=self._ph.getTxRxResult(result),
            )
        for jid, entry in self._bulk.data_dict.items():
            if len(entry[PARAM_NUM_DATA]) < entry[PARAM_NUM_LENGTH]:
                # The SDK takes the first status packet with the right ID, whatever its length: a
                # late reply to an earlier request (a loaded machine, a slow bus) lines up with this
                # one. That is a bad read, not a broken bus; drop what is queued so the next lines up.
                self.counters.read_failures += 1
                self.counters.rx_corrupt += 1
                self._discard_input()
                return ReadResult(ok=False, failed_id=jid,
                                  message=f"short reply from ID {jid} ({len(entry[PARAM_NUM_DATA])} of "
                                          f"{entry[PARAM_NUM_LENGTH]} bytes): a late status packet")
        positions = {
            jid: int(self._bulk.getData(jid, ADDR_PRESENT_POSITION, 2)) for jid in self._bulk.data_dict
        }
        return ReadResult(ok=True, positions=positions)

    def _call(self, fn: Callable[..., T], *args: Any) -> T:
        """Run one SDK call; a vanished or broken port becomes PortLost."""
        if not self._open:
            raise PortLost(f"{self.port_name} is not open")
        try:
            return fn(*args)
        except PORT_ERRORS as exc:
            self._port.is_using = False
            raise PortLost(f"{self.port_name}: {exc}") from None
        except IndexError:
            # the SDK indexes reply data without checking its length: a late or stray status
            # packet (e.g. after a timeout) can be shorter than the one it expects
            self._port.is_using = False
            self._discard_input()
            raise ReplyMismatch(f"unexpected reply on {self.port_name}") from None

    def _discard_input(self) -> None:
        """Drop bytes already received (stray or late status packets) so the next reply lines up."""
        try:
            self._port.ser.reset_input_buffer()
        except (*PORT_ERRORS, AttributeError):
            pass
