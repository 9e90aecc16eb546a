"""Dynamixel Protocol 1.0 framing, for the simulated bus only (the driver uses dynamixel-sdk).

Instruction packet: FF FF id len instr params... checksum, len = nparams + 2,
checksum = ~(id + len + instr + sum(params)) & 0xFF. A status packet has the same shape with
the error byte in the instruction's place.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import IntEnum

BROADCAST_ID = 0xFE
HEADER = b"\xff\xff"


class Instruction(IntEnum):
    PING = 0x01
    READ = 0x02
    WRITE = 0x03
    REG_WRITE = 0x04
    ACTION = 0x05
    RESET = 0x06
    SYNC_WRITE = 0x83
    BULK_READ = 0x92


class ErrorBit(IntEnum):
    VOLTAGE = 1
    ANGLE = 2
    OVERHEAT = 4
    RANGE = 8
    CHECKSUM = 16
    OVERLOAD = 32
    INSTRUCTION = 64


def checksum(body: bytes | bytearray) -> int:
    """Checksum over id, length, instruction/error and parameters."""
    return (~sum(body)) & 0xFF


@dataclass(frozen=True)
class Packet:
    """One instruction packet as received; `checksum_ok` is False when the sum did not match."""

    id: int
    instruction: int
    params: bytes
    checksum_ok: bool
    size: int
    """Bytes on the wire, header to checksum."""


def status_packet(dev_id: int, error: int = 0, params: bytes | bytearray = b"") -> bytes:
    body = bytes([dev_id, len(params) + 2, error & 0xFF]) + bytes(params)
    return HEADER + body + bytes([checksum(body)])


def instruction_packet(dev_id: int, instruction: int, params: bytes | bytearray = b"") -> bytes:
    """Build an instruction packet (used by tests that send raw or damaged packets)."""
    body = bytes([dev_id, len(params) + 2, instruction]) + bytes(params)
    return HEADER + body + bytes([checksum(body)])


class PacketReader:
    """Accumulates bytes from the wire and yields complete instruction packets, resynchronising on
    the FF FF header after garbage (as a servo's receiver does)."""

    MAX_LEN = 250

    def __init__(self) -> None:
        self._buf = bytearray()

    def feed(self, data: bytes) -> list[Packet]:
        self._buf.extend(data)
        out: list[Packet] = []
        buf = self._buf
        while True:
            start = buf.find(HEADER)
            if start < 0:
                # keep a trailing FF: it may be the first half of a header
                del buf[: max(0, len(buf) - 1) if buf.endswith(b"\xff") else len(buf)]
                break
            if start:
                del buf[:start]
            # FF FF FF ... : the id cannot be FF, skip one byte
            if len(buf) >= 3 and buf[2] == 0xFF:
                del buf[0]
                continue
            if len(buf) < 4:
                break
            length = buf[3]
            if length < 2 or length > self.MAX_LEN:
                del buf[:2]
                continue
            total = length + 4
            if len(buf) < total:
                break
            body = bytes(buf[2 : total - 1])
            ok = checksum(body) == buf[total - 1]
            out.append(Packet(id=body[0], instruction=body[2], params=body[3:], checksum_ok=ok, size=total))
            del buf[:total]
        return out

    def pending(self) -> int:
        return len(self._buf)
