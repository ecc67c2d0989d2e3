"""UDP sources read their socket in ``poll()``/``take()`` as well as on their thread: a frame
that has arrived is handed over without waiting for the thread, in order, never blocking."""

from __future__ import annotations

import socket
import threading
import time

import pytest

pytest.importorskip("pythonosc")
from pythonosc.osc_bundle_builder import IMMEDIATELY, OscBundleBuilder  # noqa: E402
from pythonosc.osc_message_builder import OscMessageBuilder  # noqa: E402

from avatar.mocap import vmc  # noqa: E402


def _frame(t: float) -> bytes:
    b = OscBundleBuilder(IMMEDIATELY)
    for address, args in (("/VMC/Ext/Bone/Pos", ["Head", 0.0, 0.1, 0.0, 0.0, 0.0, 0.0, 1.0]),
                          ("/VMC/Ext/T", [t]), ("/VMC/Ext/OK", [1])):  # fmt: skip
        m = OscMessageBuilder(address)
        for a in args:
            m.add_arg(a)
        b.add_content(m.build())
    return b.build().dgram


def _wait_readable(rx, seconds: float = 5.0) -> None:
    import select

    ready, _, _ = select.select([rx.sock], [], [], seconds)
    assert ready, "the datagram never arrived"


def test_poll_hands_over_a_frame_the_thread_has_not_read():
    rx = vmc.VmcReceiver("127.0.0.1", 0)  # not started: no thread reads the socket
    try:
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as tx:
            tx.sendto(_frame(1.0), rx.address)
            _wait_readable(rx)
            frame = rx.poll()
        assert frame is not None and frame.sent == 1.0
        assert rx.poll() is None  # handed over once
    finally:
        rx.close()


def test_take_reads_every_waiting_frame_in_order():
    rx = vmc.VmcReceiver("127.0.0.1", 0)
    try:
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as tx:
            for t in range(1, 11):
                tx.sendto(_frame(float(t)), rx.address)
            time.sleep(0.2)
            frames = rx.take()
        assert [f.sent for f in frames] == [float(t) for t in range(1, 11)]
        assert rx.stats().dropped == {}
    finally:
        rx.close()


def test_poll_never_waits_for_the_reading_thread():
    """While the thread is reading (it holds the reading lock), poll returns at once with
    what is already assembled; the waiting datagram is read once the lock is free."""
    rx = vmc.VmcReceiver("127.0.0.1", 0)
    try:
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as tx:
            tx.sendto(_frame(1.0), rx.address)
            _wait_readable(rx)
            held = threading.Event()
            release = threading.Event()

            def hold():
                with rx._reading:
                    held.set()
                    release.wait(5.0)

            holder = threading.Thread(target=hold)
            holder.start()
            held.wait(5.0)
            t = time.perf_counter()
            assert rx.poll() is None
            assert time.perf_counter() - t < 0.5
            release.set()
            holder.join()
            frame = rx.poll()
        assert frame is not None and frame.sent == 1.0
    finally:
        rx.close()


def test_thread_and_polling_reader_share_the_stream_without_losing_order():
    """The thread reads and the caller polls at the same time: every frame is taken once,
    in the sender's order (none counted out of order)."""
    rx = vmc.VmcReceiver("127.0.0.1", 0).start()
    got = []
    try:
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as tx:
            for t in range(1, 301):
                tx.sendto(_frame(float(t)), rx.address)
                got += rx.take()
                if t % 50 == 0:
                    time.sleep(0.01)
            end = time.perf_counter() + 5
            while len(got) < 300 and time.perf_counter() < end:
                time.sleep(0.01)
                got += rx.take()
    finally:
        rx.close()
    sent = [f.sent for f in got]
    assert sent == sorted(sent) and len(set(sent)) == len(sent)
    assert "out_of_order" not in rx.stats().dropped
    assert len(sent) == 300  # loopback with a 2 MB buffer loses nothing
