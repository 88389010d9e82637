"""Recovering a rosbag2 bag whose recorder was killed (SIGKILL, power loss).

Such a bag has its storage file but no ``metadata.yaml``; an MCAP file also
lacks its summary and footer, and may end in a half-written record.  What
reached the disk (the recorder commits or closes a chunk every
``flush_period``) is read back and written again as a complete bag in the
same directory and storage, so ``ros2 bag info`` and ``rosbags`` open it.
On a full ROS 2 install, ``ros2 bag reindex <bag>`` rebuilds the metadata of
a sqlite3 bag too.

Command line: ``rpr3_gwr_recover_bag <bag directory>`` (in
``lib/rpr3_gwr_nodes``, so ``ros2 run rpr3_gwr_nodes rpr3_gwr_recover_bag``).
"""

import argparse
import os
import pathlib
import struct
import sys
import tempfile

from rosbags.rosbag2 import StoragePlugin, Writer
from rosbags.rosbag2.storage_mcap import McapReader
from rosbags.rosbag2.storage_sqlite3 import Sqlite3Reader

from .bag_types import suite_typestore

__all__ = ["BagRecoveryError", "recover_bag", "main"]

_MAGIC = b"\x89MCAP0\r\n"
_OP_DATA_END, _OP_FOOTER = 0x0F, 0x02
_STORAGES = {".db3": (StoragePlugin.SQLITE3, Sqlite3Reader),
             ".mcap": (StoragePlugin.MCAP, McapReader)}


class BagRecoveryError(Exception):
    """The directory holds no bag that can be recovered."""


def recover_bag(path):
    """Rewrite a bag without ``metadata.yaml`` into a complete one, in place.

    Parameters
    ----------
    path : str or pathlib.Path
        The bag directory.

    Returns
    -------
    int
        Number of messages recovered.

    Raises
    ------
    BagRecoveryError
        If the bag has its metadata already, or no single sqlite3 or MCAP
        storage file of the bag's name.
    """
    path = pathlib.Path(path).resolve()
    if (path / "metadata.yaml").exists():
        raise BagRecoveryError(f"{path} has its metadata.yaml: nothing to recover")
    found = [path / f"{path.name}{suffix}" for suffix in _STORAGES
             if (path / f"{path.name}{suffix}").is_file()]
    if len(found) != 1:
        raise BagRecoveryError(f"{path} holds no {path.name}.db3 or {path.name}.mcap file")
    damaged = found[0]
    plugin, reader_type = _STORAGES[damaged.suffix]
    with tempfile.TemporaryDirectory(dir=path.parent) as scratch:
        scratch = pathlib.Path(scratch)
        readable = damaged
        if damaged.suffix == ".mcap":
            readable = scratch / damaged.name
            _close_mcap(damaged, readable)
        rebuilt = scratch / path.name
        count = _rewrite(reader_type(readable), rebuilt, plugin)
        os.replace(rebuilt / damaged.name, damaged)
        os.replace(rebuilt / "metadata.yaml", path / "metadata.yaml")
    return count


def _rewrite(reader, target, plugin):
    reader.open()
    try:
        writer = Writer(target, version=9, storage_plugin=plugin)
        writer.open()
        try:
            connections = {
                c.id: writer.add_connection(
                    c.topic, c.msgtype, msgdef=c.msgdef.data, rihs01=_type_hash(c),
                    serialization_format=c.ext.serialization_format,
                    offered_qos_profiles=c.ext.offered_qos_profiles)
                for c in reader.connections}
            count = 0
            for connection, stamp, raw in reader.messages(reader.connections):
                writer.write(connections[connection.id], stamp, raw)
                count += 1
        finally:
            writer.close()
    finally:
        reader.close()
    return count


def _type_hash(connection):
    """The connection's RIHS01 type hash; MCAP files do not store it, so it
    comes from the Jazzy message types and the suite's then."""
    if connection.digest:
        return connection.digest
    try:
        return suite_typestore().hash_rihs01(connection.msgtype)
    except KeyError:
        raise BagRecoveryError(f"{connection.msgtype} is neither a ROS 2 Jazzy message type "
                               "nor the suite's: its type hash is unknown") from None


def _close_mcap(source, target):
    """Copy the complete records of an MCAP file that lost its end, then
    close it with a data end and a footer without summary (MCAP readers
    then scan the records)."""
    data = source.read_bytes()
    if not data.startswith(_MAGIC):
        raise BagRecoveryError(f"{source} is not an MCAP file")
    end = offset = len(_MAGIC)
    # A record is an opcode, a uint64 length and that many bytes.
    while offset + 9 <= len(data):
        opcode, length = struct.unpack_from("<BQ", data, offset)
        if opcode in (_OP_DATA_END, _OP_FOOTER) or offset + 9 + length > len(data):
            break
        offset += 9 + length
        end = offset
    with open(target, "wb") as stream:
        stream.write(data[:end])
        stream.write(struct.pack("<BQI", _OP_DATA_END, 4, 0))
        stream.write(struct.pack("<BQQQI", _OP_FOOTER, 20, 0, 0, 0))
        stream.write(_MAGIC)


def main(argv=None):
    """``rpr3_gwr_recover_bag BAG``: recover a bag in place."""
    parser = argparse.ArgumentParser(
        prog="rpr3_gwr_recover_bag",
        description="Rebuild a rosbag2 bag whose recorder was killed (no metadata.yaml).")
    parser.add_argument("bag", help="bag directory")
    args = parser.parse_args(argv)
    try:
        count = recover_bag(args.bag)
    except (BagRecoveryError, OSError) as exc:
        print(f"rpr3_gwr_recover_bag: {exc}", file=sys.stderr)
        return 1
    print(f"recovered {count} messages in {args.bag}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
