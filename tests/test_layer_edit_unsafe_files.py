"""The layer panel reads its texture file as every texture file is read: a device, a
FIFO or a file past the size limit is one EditError, never read (a FIFO would block,
/dev/zero would never end)."""

import os

import pytest

from frictex.app.live.layer_edit import EditError, LayerEdit
from frictex.textures.toml_safe import MAX_FILE_BYTES


def test_a_link_to_a_device_is_refused_unread(tmp_path):
    link = tmp_path / "null.toml"
    link.symlink_to(os.devnull)
    with pytest.raises(EditError, match=r"cannot read null\.toml: it is a character device, "
                                        r"not a regular file"):
        LayerEdit(link)


def test_a_file_past_the_size_limit_is_refused_unread(tmp_path):
    big = tmp_path / "big.toml"
    big.write_text("format = 1\n" + "# padding\n" * (MAX_FILE_BYTES // 10))
    with pytest.raises(EditError, match=rf"cannot read big\.toml: it is {big.stat().st_size:,} "
                                        rf"bytes, more than the {MAX_FILE_BYTES:,} bytes"):
        LayerEdit(big)
