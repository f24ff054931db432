"""CPU steal from /proc/stat: parsed by column, and None wherever it cannot be measured."""

from frictex.app.live.cpu_steal import StealMeter, cpu_times


def write(path, steal, other):
    # user nice system idle iowait irq softirq steal guest guest_nice
    path.write_text(f"cpu  {other} 0 {other} {other} 0 0 0 {steal} 7 7\ncpu0 1 2 3 4 5 6 7 8 0 0\n")


def test_steal_share_between_two_readings(tmp_path):
    stat = tmp_path / "stat"
    write(stat, steal=100, other=300)  # total 1000
    assert cpu_times(stat) == (100, 1000)
    meter = StealMeter(stat)
    write(stat, steal=130, other=390)  # +30 steal of +300
    assert meter.percent() == 10.0


def test_unmeasurable_is_none(tmp_path):
    assert StealMeter(tmp_path / "missing").percent() is None
    old = tmp_path / "old"
    old.write_text("cpu  1 2 3 4\n")  # no steal column
    assert cpu_times(old) is None
    stat = tmp_path / "stat"
    write(stat, steal=1, other=1)
    assert StealMeter(stat).percent() is None  # no time passed
