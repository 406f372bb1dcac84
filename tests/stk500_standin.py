"""A stand-in for the Arduino Uno's bootloader (STK500 version 1), on a pseudo-terminal.

``make -C firmware flash`` runs ``avrdude -c arduino``, which speaks STK500v1 to the
board's bootloader. This stand-in answers the commands avrdude sends (sync, parameters,
device set-up, signature of an ATmega328P, load address, program page, read page),
keeps what is written in a 32 KiB flash image, and lets avrdude read it back to verify.
It is written from Atmel's application note AVR061 (STK500 communication protocol).

    python tests/stk500_standin.py --check firmware/build/daq.hex -- make -C firmware flash

runs the command with ``PORT`` set to the pseudo-terminal, then checks that the flash
image equals the hex file; exit status 0 only if both the command and the check pass.
"""

from __future__ import annotations

import argparse
import os
import select
import subprocess
import sys
import threading
import tty
from pathlib import Path

INSYNC, OK, EOP = 0x14, 0x10, 0x20
SIGNATURE_M328P = bytes([0x1E, 0x95, 0x0F])
FLASH_BYTES = 32 * 1024
# Bytes that follow the command byte, before CRC_EOP, for the fixed-length commands.
ARGUMENTS = {0x30: 0, 0x31: 0, 0x40: 2, 0x41: 1, 0x42: 20, 0x50: 0, 0x51: 0, 0x52: 0,
             0x55: 2, 0x56: 4, 0x75: 0, 0x76: 0}
PARAMETERS = {0x80: 2, 0x81: 8, 0x82: 0}   # hardware version, firmware 8.0 (optiboot's)


class Bootloader:
    """Serves STK500v1 on the master side of a pty until the client closes it."""

    def __init__(self, signature: bytes = SIGNATURE_M328P) -> None:
        self.signature = signature
        self.master, slave = os.openpty()
        tty.setraw(slave)
        self.port = os.ttyname(slave)
        self._slave = slave      # held open so the pty survives between avrdude's opens
        self.flash = bytearray(b"\xff" * FLASH_BYTES)
        self.pages_written = 0
        self._address = 0        # in bytes
        self._stop = threading.Event()
        self._buffer = bytearray()
        self._thread = threading.Thread(target=self._serve, daemon=True)

    def __enter__(self) -> Bootloader:
        self._thread.start()
        return self

    def __exit__(self, *exc) -> None:
        self._stop.set()
        self._thread.join(timeout=2)
        os.close(self.master)
        os.close(self._slave)

    def _read(self, n: int) -> bytes:
        while len(self._buffer) < n:
            if self._stop.is_set():
                raise EOFError
            ready, _, _ = select.select([self.master], [], [], 0.05)
            if ready:
                try:
                    self._buffer += os.read(self.master, 4096)
                except OSError:
                    raise EOFError from None
        out, self._buffer = bytes(self._buffer[:n]), self._buffer[n:]
        return out

    def _reply(self, payload: bytes = b"") -> None:
        if self._read(1)[0] != EOP:          # a command not framed by CRC_EOP: out of sync
            os.write(self.master, bytes([0x15]))
            return
        os.write(self.master, bytes([INSYNC]) + payload + bytes([OK]))

    def _serve(self) -> None:
        try:
            while True:
                self._command(self._read(1)[0])
        except EOFError:
            pass

    def _command(self, cmd: int) -> None:
        if cmd in ARGUMENTS:
            args = self._read(ARGUMENTS[cmd])
            if cmd == 0x41:
                self._reply(bytes([PARAMETERS.get(args[0], 3)]))
            elif cmd == 0x55:                      # word address, little-endian
                self._address = 2 * (args[0] | args[1] << 8)
                self._reply()
            elif cmd == 0x56:
                self._reply(b"\x00")
            elif cmd == 0x75:
                self._reply(self.signature)
            else:
                self._reply()
        elif cmd == 0x45:                          # SET_DEVICE_EXT: a count byte, then count-1
            self._read(self._read(1)[0] - 1)
            self._reply()
        elif cmd in (0x64, 0x74):                  # PROG_PAGE / READ_PAGE: size, memtype
            size_hi, size_lo, memtype = self._read(3)
            size = size_hi << 8 | size_lo
            if cmd == 0x64:
                data = self._read(size)
                if memtype == ord("F"):
                    self.flash[self._address:self._address + size] = data
                    self.pages_written += 1
                self._reply()
            else:
                self._reply(bytes(self.flash[self._address:self._address + size]))
        # Anything else is line noise (avrdude drains and re-syncs): ignore the byte.


def read_hex(path: Path) -> dict[int, int]:
    """The bytes of an Intel HEX file, by address (record types 00, 01, 02 and 04)."""
    data, base = {}, 0
    for number, line in enumerate(path.read_text().split(), 1):
        raw = bytes.fromhex(line.lstrip(":"))
        if sum(raw) & 0xFF:
            raise ValueError(f"{path}:{number}: bad checksum")
        count, address, kind = raw[0], raw[1] << 8 | raw[2], raw[3]
        payload = raw[4:4 + count]
        if kind == 0:
            data.update({base + address + i: b for i, b in enumerate(payload)})
        elif kind == 2:
            base = (payload[0] << 8 | payload[1]) << 4
        elif kind == 4:
            base = (payload[0] << 8 | payload[1]) << 16
    return data


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--check", type=Path, help="an Intel HEX file the flash must equal afterwards")
    parser.add_argument("command", nargs=argparse.REMAINDER, help="-- then the command; PORT is set for it")
    args = parser.parse_args(argv)
    command = args.command[1:] if args.command[:1] == ["--"] else args.command
    with Bootloader() as board:
        rc = subprocess.run(command, env={**os.environ, "PORT": board.port}).returncode
    print(f"stk500_standin: {board.pages_written} pages written on {board.port}; command exit {rc}")
    if rc or args.check is None:
        return rc
    image = read_hex(args.check)
    bad = [a for a, b in image.items() if board.flash[a] != b]
    print(f"stk500_standin: {len(image)} bytes of {args.check}: "
          + ("flash matches" if not bad else f"{len(bad)} differ, first at 0x{bad[0]:04x}"))
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
