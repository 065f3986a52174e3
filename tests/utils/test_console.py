"""Console output: what a failing quiet block had printed comes back, Warp's no-driver warning alone is dropped,
benchmark tables are titled Markdown blocks."""

import sys

from refpo_warp.utils.console import quiet_stdout


def test_quiet_stdout_replays_what_it_hid_when_the_block_fails(capsys):
    try:
        with quiet_stdout():
            print("a clue")
            raise RuntimeError("boom")
    except RuntimeError:
        pass
    captured = capsys.readouterr()
    assert captured.out == "" and "a clue" in captured.err


def test_only_warps_no_driver_warning_is_dropped(capfd):
    import os

    from refpo_warp.utils.warp_setup import NO_DRIVER_WARNING, _stderr_without

    with _stderr_without(NO_DRIVER_WARNING):  # native code writes to file descriptor 2, as Warp's library does
        os.write(2, f"Warp CUDA warning: {NO_DRIVER_WARNING}. GPU execution will not be available.\n".encode())
        os.write(2, b"Warp CUDA error: something else\n")
        print("python-level warning", file=sys.stderr)
    err = capfd.readouterr().err
    assert NO_DRIVER_WARNING not in err
    assert "Warp CUDA error: something else" in err and "python-level warning" in err


def test_benchmark_tables_are_titled_blocks(capsys):
    from refpo_warp.utils.timing import print_table

    print_table([{"a": 1, "b": "x"}], ["a", "b"], title="First", notes=("ratio 2.0x",))
    print_table([{"a": 22}], ["a"], title="Second")
    lines = capsys.readouterr().out.split("\n")
    assert lines[:7] == ["", "### First", "", "| a | b |", "|---|---|", "| 1 | x |", ""]
    assert lines[7:10] == ["ratio 2.0x", "", "### Second"]  # one blank line before each title
