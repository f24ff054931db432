"""A file a texture file names is checked, opened and read once: swapping the path
after the check (for a link, or a folder on the way for a link) reads nothing outside."""

import os
from pathlib import Path

import pytest

from frictex.device.safe_files import UnsafeFile, pinned, read_bytes
from frictex.textures.schema import Reader
from frictex.textures.sections.files import Files


class Recorder(Reader):
    def __init__(self):
        self.problems = []

    def report(self, path, message):
        self.problems.append(message)


def _read(files, name):
    r = Recorder()
    got = files.read(r, ("layer", 0, "image"), name, lambda f: read_bytes(f, 1 << 20))
    return got, r.problems


@pytest.fixture
def folders(tmp_path):
    inside, outside = tmp_path / "scene", tmp_path / "elsewhere"
    (inside / "sub").mkdir(parents=True)
    outside.mkdir()
    (inside / "sub" / "map.png").write_bytes(b"inside")
    (outside / "map.png").write_bytes(b"SECRET")
    return inside, outside


def test_a_file_swapped_for_a_link_after_the_check_is_not_read(folders, monkeypatch):
    inside, outside = folders
    files = Files(inside)
    checked = Files.locate

    def swap_after_check(self, name):
        real = checked(self, name)
        os.unlink(real)
        os.symlink(outside / "map.png", real)
        return real
    monkeypatch.setattr(Files, "locate", swap_after_check)
    got, problems = _read(files, "sub/map.png")
    assert got is None and "became a symbolic link after it was checked" in problems[0]


def test_a_folder_swapped_for_a_link_after_the_check_is_not_read(folders, monkeypatch):
    inside, outside = folders
    files = Files(inside)
    checked = Files.locate

    def swap_after_check(self, name):
        real = checked(self, name)
        os.rename(inside / "sub", inside / "old")
        os.symlink(outside, inside / "sub")
        return real
    monkeypatch.setattr(Files, "locate", swap_after_check)
    got, problems = _read(files, "sub/map.png")
    assert got is None and "outside the texture file's folder, when it was opened" in problems[0]
    assert "SECRET" not in problems[0]


def test_the_reader_reads_the_file_opened_not_the_path_again(folders):
    """Swapped after the open, while the reader runs: the reader still gets the
    checked file's bytes."""
    inside, outside = folders
    files = Files(inside)

    def swapping_reader(path):
        os.unlink(path)
        os.symlink(outside / "map.png", path)
        return read_bytes(path, 1 << 20)
    r = Recorder()
    got = files.read(r, ("image",), "sub/map.png", swapping_reader)
    assert r.problems == [] and got[1] == b"inside"


def test_a_missing_file_is_said_in_the_readers_words(folders):
    inside, _ = folders
    got, problems = _read(Files(inside), "sub/none.png")
    assert got is None and len(problems) == 1 and "none.png" in problems[0]


def test_pinned_reads_the_descriptor_and_a_pinned_phrase_opens_nothing(tmp_path):
    path = tmp_path / "a.bin"
    path.write_bytes(b"first")
    fd = os.open(path, os.O_RDONLY)
    try:
        os.unlink(path)
        path.write_bytes(b"second")
        with pinned(path, fd):
            assert read_bytes(path, 100) == b"first" and read_bytes(path, 100) == b"first"
        assert read_bytes(path, 100) == b"second"
    finally:
        os.close(fd)
    with pinned(Path(path), "is gone"), pytest.raises(UnsafeFile, match="is gone"):
        read_bytes(path, 100)
