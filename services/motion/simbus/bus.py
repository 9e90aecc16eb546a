"""A simulated OP2 Dynamixel bus on a pseudo-terminal: a CM-740 plus twenty MX-28 servos.

Any Dynamixel tool (here: the real dynamixel-sdk) opens `SimBus.path` as a serial port and talks
Protocol 1.0 to it. Wire time at the bus baud rate is modelled: an instruction occupies the bus for
10 bits per byte, each status packet follows after the device's return delay, and replies are
written to the pty when their last byte would have arrived. Servos answer only while the CM-740
powers the bus (address 24), as on the robot.

Fault injection (thread-safe, for tests): `silence(id)` / `revive(id)`, `corrupt_replies(n)`.
"""

from __future__ import annotations

import os
import select
import threading
import time
import tty
from collections import deque
from collections.abc import Iterable
from dataclasses import dataclass, field
from typing import Self

from services.motion.joints import CM740_ID, JOINT_IDS, SIT
from services.motion.protocol import BROADCAST_ID, ErrorBit, Instruction, Packet, PacketReader, status_packet
from services.motion.simbus.devices import CM740, MX28, Device
from services.runtime import get_logger

BOOT_DELAY_S = 0.05
"""Servos answer this long after the CM-740 powers the bus."""


@dataclass
class BusStats:
    packets: int = 0
    bad_checksums: int = 0
    sync_writes: int = 0
    bulk_reads: int = 0
    replies: int = 0
    corrupted: int = 0
    sync_write_log: deque[tuple[float, dict[int, int]]] = field(default_factory=lambda: deque(maxlen=4000))
    """(time.time(), {id: goal position}) of recent SYNC_WRITEs that carried goal positions."""


class SimBus:
    """Serve a simulated OP2 bus on a fresh pty until `stop()`."""

    def __init__(
        self,
        positions: dict[int, float] | None = None,
        *,
        powered: bool = False,
        baud: int = 1_000_000,
        wire_time: bool = True,
    ) -> None:
        start = positions if positions is not None else SIT
        self.cm740 = CM740(CM740_ID)
        self.servos: dict[int, MX28] = {jid: MX28(jid, round(start.get(jid, 2048))) for jid in JOINT_IDS}
        self.byte_time = 10.0 / baud if wire_time else 0.0
        self.stats = BusStats()
        self.log = get_logger("simbus")
        self._lock = threading.RLock()
        self._silent: set[int] = set()
        self._corrupt_left = 0
        self._stray: list[int] = []
        self._booted_at: float | None = None
        self._bus_free = 0.0
        self._reader = PacketReader()
        self._devices: dict[int, Device] = {}
        self._master, self._slave = os.openpty()
        tty.setraw(self._slave)
        self.path = os.ttyname(self._slave)
        self._wake_r, self._wake_w = os.pipe()
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self._closed = False
        self._reindex()
        if powered:
            self.cm740.set("dynamixel_power", 1)
            self._booted_at = time.monotonic()

    # ------------------------------------------------------------------ lifecycle
    def start(self) -> Self:
        self._thread = threading.Thread(target=self.serve_forever, name="simbus", daemon=True)
        self._thread.start()
        return self

    def stop(self) -> None:
        self._stop.set()
        try:
            os.write(self._wake_w, b"x")
        except OSError:
            pass
        if self._thread is not None and self._thread is not threading.current_thread():
            self._thread.join(2.0)
        self.close()

    def close(self) -> None:
        if self._closed:
            return
        self._closed = True
        for fd in (self._master, self._slave, self._wake_r, self._wake_w):
            try:
                os.close(fd)
            except OSError:
                pass

    def __enter__(self) -> Self:
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.stop()

    def serve_forever(self) -> None:
        while not self._stop.is_set():
            try:
                ready, _, _ = select.select([self._master, self._wake_r], [], [])
            except (OSError, ValueError):
                return
            if self._wake_r in ready:
                return
            try:
                data = os.read(self._master, 4096)
            except OSError:
                return
            arrived = time.monotonic()
            for packet in self._reader.feed(data):
                self._serve_packet(packet, arrived)

    # ------------------------------------------------------------------ fault injection / inspection
    def silence(self, *ids: int) -> None:
        """These devices stop answering (a broken cable or a dead servo)."""
        with self._lock:
            self._silent.update(ids)

    def revive(self, *ids: int) -> None:
        with self._lock:
            self._silent.difference_update(ids)

    def corrupt_replies(self, count: int) -> None:
        """The next `count` status packets go out with a wrong checksum."""
        with self._lock:
            self._corrupt_left = count

    def stray_reply(self, dev_id: int) -> None:
        """The next BULK_READ answer is preceded by a late status packet from `dev_id` carrying no
        data (the answer to an earlier request that had already timed out, as on a loaded host)."""
        with self._lock:
            self._stray.append(dev_id)

    def set_power(self, on: bool) -> None:
        with self._lock:
            was = self.cm740.power
            self.cm740.set("dynamixel_power", 1 if on else 0)
            self._power_changed(was, on, time.monotonic())

    def present_positions(self) -> dict[int, int]:
        with self._lock:
            now = time.monotonic()
            for servo in self.servos.values():
                servo.advance(now)
            return {jid: s.get("present_position") for jid, s in self.servos.items()}

    def goal_positions(self) -> dict[int, int]:
        with self._lock:
            return {jid: s.get("goal_position") for jid, s in self.servos.items()}

    def torque(self) -> dict[int, bool]:
        with self._lock:
            return {jid: bool(s.get("torque_enable")) for jid, s in self.servos.items()}

    @property
    def powered(self) -> bool:
        return self.cm740.power

    # ------------------------------------------------------------------ protocol
    def _reindex(self) -> None:
        self._devices = {d.id: d for d in (self.cm740, *self.servos.values())}

    def _alive(self, dev_id: int, now: float) -> Device | None:
        """The device that would answer `dev_id` now, or None (absent, unpowered, booting, silenced)."""
        dev = self._devices.get(dev_id)
        if dev is None or dev_id in self._silent:
            return None
        booting = self._booted_at is None or now < self._booted_at
        if isinstance(dev, MX28) and (not self.cm740.power or booting):
            return None
        return dev

    def _power_changed(self, was: bool, on: bool, now: float) -> None:
        if on and not was:
            self._booted_at = now + BOOT_DELAY_S
            for servo in self.servos.values():
                servo.reset_ram()
        elif was and not on:
            for servo in self.servos.values():
                servo.advance(now)
                servo.set("torque_enable", 0)
            self._booted_at = None

    def _serve_packet(self, packet: Packet, arrived: float) -> None:
        replies: list[bytes] = []
        with self._lock:
            self.stats.packets += 1
            start = max(arrived, self._bus_free)
            now = start + packet.size * self.byte_time
            if self.cm740.power:
                for servo in self.servos.values():
                    servo.advance(now)
            if not packet.checksum_ok:
                self.stats.bad_checksums += 1
                dev = self._alive(packet.id, now) if packet.id != BROADCAST_ID else None
                if dev is not None:
                    replies.append(self._status(dev, ErrorBit.CHECKSUM))
            elif packet.instruction == Instruction.SYNC_WRITE:
                self._sync_write(packet, now)
            elif packet.instruction == Instruction.BULK_READ:
                stray = [self._status(d, 0) for i in self._stray if (d := self._alive(i, now)) is not None]
                self._stray.clear()
                replies.extend([*stray, *self._bulk_read(packet, now)])
            elif packet.id == BROADCAST_ID:
                if packet.instruction == Instruction.WRITE and len(packet.params) >= 2:
                    for dev_id in list(self._devices):
                        dev = self._alive(dev_id, now)
                        if dev is not None:
                            self._write(dev, packet.params[0], packet.params[1:], now)
            else:
                dev = self._alive(packet.id, now)
                if dev is not None:
                    reply = self._single(dev, packet, now)
                    if reply is not None:
                        replies.append(reply)
            end = now
            for reply in replies:
                end += self._delay(reply) + len(reply) * self.byte_time
            self._bus_free = end
            self.stats.replies += len(replies)
        if replies:
            wait = end - time.monotonic()
            if wait > 0:
                time.sleep(wait)
            try:
                os.write(self._master, b"".join(replies))
            except OSError:
                pass

    def _delay(self, reply: bytes) -> float:
        dev = self._devices.get(reply[2])
        return dev.return_delay_s if dev is not None else 0.0

    def _status(self, dev: Device, error: int, params: bytes = b"") -> bytes:
        packet = status_packet(dev.id, error, params)
        if self._corrupt_left > 0:
            self._corrupt_left -= 1
            self.stats.corrupted += 1
            packet = packet[:-1] + bytes([packet[-1] ^ 0x5A])
        return packet

    def _single(self, dev: Device, packet: Packet, now: float) -> bytes | None:
        instr, params = packet.instruction, packet.params
        level = dev.status_return_level
        if instr == Instruction.PING:
            return self._status(dev, 0)
        if instr == Instruction.READ:
            if len(params) != 2:
                return self._status(dev, ErrorBit.INSTRUCTION) if level >= 1 else None
            error, data = dev.read(params[0], params[1])
            return self._status(dev, error, data) if level >= 1 else None
        if instr == Instruction.WRITE:
            if len(params) < 2:
                return self._status(dev, ErrorBit.INSTRUCTION) if level >= 2 else None
            error = self._write(dev, params[0], params[1:], now)
            return self._status(dev, error) if level >= 2 else None
        return self._status(dev, ErrorBit.INSTRUCTION) if level >= 1 else None

    def _write(self, dev: Device, addr: int, data: bytes, now: float) -> int:
        was_powered = self.cm740.power
        error = dev.write(addr, bytes(data))
        if dev is self.cm740 and self.cm740.power != was_powered:
            self._power_changed(was_powered, self.cm740.power, now)
        if addr <= 3 < addr + len(data):
            self._reindex()
        return error

    def _sync_write(self, packet: Packet, now: float) -> None:
        params = packet.params
        if packet.id != BROADCAST_ID or len(params) < 2:
            return
        start, length = params[0], params[1]
        chunk = length + 1
        body = params[2:]
        if length == 0 or len(body) % chunk:
            return
        goals: dict[int, int] = {}
        for i in range(0, len(body), chunk):
            dev_id, data = body[i], body[i + 1 : i + chunk]
            dev = self._alive(dev_id, now)
            if dev is None:
                continue
            self._write(dev, start, data, now)
            if isinstance(dev, MX28) and start <= 30 and start + length >= 32:
                goals[dev_id] = dev.get("goal_position")
        self.stats.sync_writes += 1
        if goals:
            self.stats.sync_write_log.append((time.time(), goals))

    def _bulk_read(self, packet: Packet, now: float) -> Iterable[bytes]:
        """Devices answer in the order asked; each waits for the previous one, so a silent device
        ends the chain (as Protocol 1.0 devices do)."""
        params = packet.params
        if packet.id != BROADCAST_ID or len(params) < 4 or (len(params) - 1) % 3:
            return []
        self.stats.bulk_reads += 1
        replies: list[bytes] = []
        for i in range(1, len(params), 3):
            length, dev_id, addr = params[i], params[i + 1], params[i + 2]
            dev = self._alive(dev_id, now)
            if dev is None:
                break
            error, data = dev.read(addr, length)
            replies.append(self._status(dev, error, data))
        return replies
