"""The svokit container (formats/container.md): header, section table, 64-byte aligned payloads.

Every check of the spec's "What a reader checks" is made before a payload is handed out; a
section may be left unverified at open (``lazy``) when its parts carry checksums of their own, as
an .svo's PAGE does (each page is checked when it is read).
"""

import mmap
import struct

from .errors import FormatError

try:  # Debian's python3-crc32c: hardware CRC-32C. The fallback is table-driven, in Python.
    from crc32c import crc32c as _crc32c_fast
except ImportError:  # pragma: no cover - exercised only without the package
    _crc32c_fast = None

_HEADER = struct.Struct("<8sIIQII")
_ENTRY = struct.Struct("<4sIQQII")
HEADER_SIZE = _HEADER.size
ENTRY_SIZE = _ENTRY.size


def _crc32c_table():
    table = []
    for i in range(256):
        c = i
        for _ in range(8):
            c = (c >> 1) ^ 0x82F63B78 if c & 1 else c >> 1
        table.append(c)
    return table


_TABLE = None


def crc32c(data, crc=0):
    """CRC-32C (Castagnoli) of ``data``, continuing from ``crc``."""
    if _crc32c_fast is not None:
        return _crc32c_fast(data, crc)
    global _TABLE
    if _TABLE is None:
        _TABLE = _crc32c_table()
    c = crc ^ 0xFFFFFFFF
    for b in bytes(data):
        c = (c >> 8) ^ _TABLE[(c ^ b) & 0xFF]
    return c ^ 0xFFFFFFFF


class Section:
    __slots__ = ("tag", "offset", "size", "crc")

    def __init__(self, tag, offset, size, crc):
        self.tag, self.offset, self.size, self.crc = tag, offset, size, crc


class Container:
    """A container file, mapped read-only. ``sections`` maps tag to Section, in table order."""

    def __init__(self, path, magic, newest_version, lazy=()):
        self.path = str(path)
        try:
            with open(path, "rb") as f:
                size = f.seek(0, 2)
                if size == 0:
                    raise FormatError(self.path, "empty file")
                self._map = mmap.mmap(f.fileno(), 0, access=mmap.ACCESS_READ)
        except OSError as e:
            raise FormatError(self.path, e.strerror or str(e)) from None
        # Slices of the mapping are bytes, copies: no view outlives close() or an exception.
        self.data = self._map
        try:
            self._read_frame(magic, newest_version, size, lazy)
        except FormatError:
            self._map.close()
            raise

    def _read_frame(self, magic, newest_version, size, lazy):
        if size < HEADER_SIZE:
            self.fail(f"truncated: {size} bytes, the header alone is {HEADER_SIZE}")
        got_magic, version, flags, file_size, count, header_crc = _HEADER.unpack_from(self.data, 0)
        if got_magic != magic:
            self.fail(f"not a {magic[1:4].decode()} file (magic {got_magic.hex(' ')})")
        if version == 0 or version > newest_version:
            self.fail(f"version {version} is not supported (this reader reads up to {newest_version})")
        if file_size != size:
            self.fail(f"header says {file_size} bytes, the file has {size}")
        table_end = HEADER_SIZE + ENTRY_SIZE * count
        if table_end > size:
            self.fail(f"section table of {count} entries runs past the end")
        crc = crc32c(self.data[:28])
        crc = crc32c(self.data[HEADER_SIZE:table_end], crc)
        if crc != header_crc:
            self.fail("header checksum mismatch")
        self.version, self.flags, self.size = version, flags, size
        self.sections = {}
        prev_end = table_end
        for i in range(count):
            expected = _align(prev_end)
            tag, _, offset, length, crc, _ = _ENTRY.unpack_from(self.data, HEADER_SIZE + ENTRY_SIZE * i)
            name = tag.decode("latin-1")
            if offset != expected or offset + length > size:
                self.fail(f"section {name} at {offset} (+{length}) is not where the layout puts it")
            if any(self.data[prev_end:offset]):
                self.fail(f"padding before section {name} is not zero")
            if name in self.sections:
                self.fail(f"section {name} appears twice")
            section = Section(name, offset, length, crc)
            if name not in lazy and crc32c(self.data[offset:offset + length]) != crc:
                self.fail(f"section {name} checksum mismatch")
            self.sections[name] = section
            prev_end = offset + length
        if prev_end != size:
            self.fail(f"{size - prev_end} bytes after the last section")

    def fail(self, problem):
        raise FormatError(self.path, problem)

    def payload(self, tag, required=True):
        """The payload of section ``tag`` (bytes), or None when absent and not required."""
        s = self.sections.get(tag)
        if s is None:
            if required:
                self.fail(f"no {tag} section")
            return None
        return self.data[s.offset:s.offset + s.size]

    def verify(self, tag):
        """Checks a section left unverified at open."""
        s = self.sections[tag]
        if crc32c(self.data[s.offset:s.offset + s.size]) != s.crc:
            self.fail(f"section {tag} checksum mismatch")

    def close(self):
        self._map.close()


def _align(n):
    return (n + 63) // 64 * 64
