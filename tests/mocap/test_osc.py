"""The OSC decoder of the receivers against python-osc (the independent implementation), on
valid packets of every argument type, and on garbage (OscError, nothing else)."""

from __future__ import annotations

import struct

import numpy as np
import pytest
from pythonosc.osc_bundle_builder import IMMEDIATELY, OscBundleBuilder
from pythonosc.osc_message_builder import OscMessageBuilder
from pythonosc.osc_packet import OscPacket

from avatar.mocap import osc, unity
from avatar.rig import quaternion


def _msg(address, *args, types=None):
    m = OscMessageBuilder(address)
    for i, a in enumerate(args):
        m.add_arg(a, None if types is None else types[i])
    return m.build()


def _bundle(*contents):
    b = OscBundleBuilder(IMMEDIATELY)
    for c in contents:
        b.add_content(c)
    return b.build()


def _theirs(dgram: bytes) -> list[tuple[str, list]]:
    return [(str(m.message.address), list(m.message.params)) for m in OscPacket(dgram).messages]


VALID = [
    _msg("/VMC/Ext/Bone/Pos", "LeftUpperArm", 0.1, 0.2, -0.3, 0.0, 0.0, 0.7071, 0.7071),
    _msg("/VMC/Ext/OK", 1),
    _msg("/VMC/Ext/T", 12.5),
    _msg("/VMC/Ext/Blend/Apply"),
    _msg("/a/b", "", "abc", "abcd", "é"),  # strings of every padding, UTF-8
    _msg("/ints", -(2**31), 2**31 - 1, 0, types="iii"),
    _msg("/wide", 2**40, 1.5, types="hd"),
    _msg("/blob", b"x", b"abcd", b"abcde"),
    _msg("/flags", True, False, None, types="TFN"),
    _msg("/array", [1, 2.5, "s"], 3),
    _msg("/nested", [[1, 2], []], types=None),
]


@pytest.mark.parametrize("packet", VALID, ids=lambda p: p.address)
def test_messages_decode_as_python_osc_reads_them(packet):
    assert osc.decode(packet.dgram) == _theirs(packet.dgram)


def test_bundles_flatten_in_order_nested_too():
    inner = _bundle(VALID[1], VALID[2])
    outer = _bundle(VALID[0], inner, VALID[4])
    got = osc.decode(outer.dgram)
    assert got == _theirs(outer.dgram)
    assert [a for a, _ in got] == ["/VMC/Ext/Bone/Pos", "/VMC/Ext/OK", "/VMC/Ext/T", "/a/b"]
    assert got[0][1][0] == "LeftUpperArm"
    np.testing.assert_allclose(got[0][1][1:], [0.1, 0.2, -0.3, 0.0, 0.0, 0.7071, 0.7071],
                               rtol=1e-7)  # float32 on the wire  # fmt: skip


def test_a_vmc_frame_of_every_humanoid_bone_decodes_like_python_osc():
    rng = np.random.default_rng(0)
    bones = [
        _msg("/VMC/Ext/Bone/Pos", name, *rng.normal(size=3).tolist(), *rng.normal(size=4).tolist())
        for name, _, _ in unity.human_bones()
    ]
    frame = _bundle(_msg("/VMC/Ext/Root/Pos", "root", *[0.0] * 6, 1.0), *bones,
                    _msg("/VMC/Ext/OK", 1), _msg("/VMC/Ext/T", 3.25))  # fmt: skip
    assert osc.decode(frame.dgram) == _theirs(frame.dgram)


GOOD = _bundle(VALID[0], VALID[1]).dgram
GARBAGE = [
    b"",  # nothing
    b"abc",  # no address
    b"/a\x00",  # address not padded
    b"/a\x00\x00x\x00\x00\x00",  # type tag without its comma
    b"/abc",  # unterminated address
    b"/a\x00\x00,f\x00\x00\x00\x00",  # a float cut short
    b"/a\x00\x00,f\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00",  # bytes after the arguments
    b"/a\x00\x00,q\x00\x00",  # unknown type tag
    b"/a\x00\x00,[i\x00\x00\x00\x00\x01",  # array never closed
    b"/a\x00\x00,]\x00\x00",  # closed, never opened
    b"/a\x00\x00,s\x00\x00\xff\xfe\x00\x00",  # a string that is not UTF-8
    b"/a\x00\x00,b\x00\x00\x7f\xff\xff\xff",  # a blob larger than the packet
    b"#bundle\x00" + b"\x00" * 4,  # a header cut short
    b"#bundle\x00" + b"\x00" * 8 + struct.pack(">i", 2**31 - 1) + b"abc",  # huge element
    b"#bundle\x00" + b"\x00" * 8 + struct.pack(">i", -4),  # negative size
    b"#bundle\x00" + b"\x00" * 8 + struct.pack(">i", 6) + b"/a\x00\x00,\x00",  # size not x4
    GOOD[:-3],  # truncated
]


@pytest.mark.parametrize("data", GARBAGE, ids=range(len(GARBAGE)))
def test_garbage_raises_osc_error(data):
    with pytest.raises(osc.OscError):
        osc.decode(data)


def test_bundles_nested_past_the_limit_are_refused():
    packet = VALID[1]
    for _ in range(12):
        packet = _bundle(packet)
    with pytest.raises(osc.OscError, match="nested"):
        osc.decode(packet.dgram)


def test_random_bytes_raise_nothing_but_osc_error():
    rng = np.random.default_rng(7)
    datagrams = [rng.bytes(int(rng.integers(0, 300))) for _ in range(3000)]
    datagrams += [GOOD[: int(rng.integers(0, len(GOOD)))] for _ in range(300)]
    # flipped bytes inside a good frame: sizes, tags and strings go wrong in every way
    for _ in range(1000):
        b = bytearray(GOOD)
        b[int(rng.integers(0, len(b)))] = int(rng.integers(0, 256))
        datagrams.append(bytes(b))
    decoded = 0
    for data in datagrams:
        try:
            messages = osc.decode(data)
        except osc.OscError:
            continue
        decoded += 1
        assert all(isinstance(a, str) and isinstance(p, list) for a, p in messages)
    assert decoded > 100  # many flipped float bytes are still valid OSC


def test_the_one_product_hamilton_form_matches_quaternion_multiply():
    rng = np.random.default_rng(1)
    a, b = rng.normal(size=(50, 4)), rng.normal(size=(50, 4))
    np.testing.assert_allclose(unity._multiply(a, b), quaternion.multiply(a, b), atol=1e-14)
    np.testing.assert_allclose(unity._multiply(a[:1], b), quaternion.multiply(a[:1], b),
                               atol=1e-14)  # fmt: skip
