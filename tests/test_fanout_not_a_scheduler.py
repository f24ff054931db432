"""--scheduler at a server that is not a Dask scheduler: one line and exit 1, within the
connect's deadline. A silent one held ``frictex batch`` for ever; one that answers in
another protocol had its bytes read as a frame's length (a MemoryError of 3 EiB), exit 70."""

import socket
import threading

import pytest

from frictex.app.commands.cli import main
from frictex.app.engine import fanout

pytest.importorskip("distributed", reason="dask.distributed is not installed "
                    "(pip install 'frictex[cluster]')")

MANIFEST = "scene,trace,name\ngrating-5mm,swipe-40mms-50hz,a\n"
#: the most (s) a command may take with CONNECT_S at 1 s before it counts as hung
BOUND_S = 60


@pytest.fixture(params=["silent", "banner"])
def server(request):
    """The address of a loopback server that accepts and says nothing, or sends an HTTP
    error and hangs up."""
    listener = socket.create_server(("127.0.0.1", 0))
    kept = []

    def serve():
        while True:
            try:
                conn, _ = listener.accept()
            except OSError:  # the listener closed: the test is over
                return
            if request.param == "banner":
                conn.sendall(b"HTTP/1.1 400 Bad Request\r\nContent-Length: 0\r\n\r\n")
                conn.close()
            else:
                kept.append(conn)

    threading.Thread(target=serve, daemon=True).start()
    yield f"tcp://127.0.0.1:{listener.getsockname()[1]}"
    listener.close()
    for conn in kept:
        conn.close()


def run_bounded(argv: list[str]) -> int:
    """``main(argv)``'s exit code; fails the test if it has not ended within BOUND_S."""
    codes = []
    thread = threading.Thread(target=lambda: codes.append(main(argv)), daemon=True)
    thread.start()
    thread.join(BOUND_S)
    assert not thread.is_alive(), f"{argv[0]} still connecting after {BOUND_S} s"
    return codes[0]


@pytest.mark.parametrize("command", ["batch", "report"])
def test_a_server_that_is_not_a_scheduler_is_one_line(tmp_path, capsys, monkeypatch, server,
                                                      command):
    monkeypatch.setattr(fanout, "CONNECT_S", 1.0)
    (tmp_path / "m.csv").write_text(MANIFEST)
    argv = (["batch", str(tmp_path / "m.csv"), "--out", str(tmp_path / "o"), "--quiet"]
            if command == "batch" else
            ["report", "--quick", "--scenes", "grating-5mm", "--out", str(tmp_path / "o"),
             "--no-progress"])
    assert run_bounded(argv + ["--scheduler", server]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1
    assert err[0].startswith(f"frictex: error: cannot reach the Dask scheduler at {server}: ")
