"""``tightknot bench knots``: its input checks (the timed run itself is a benchmark, run
by hand: speed targets never live in tests)."""

import pytest

from tightknot.app.cli import main


@pytest.mark.parametrize("argv, match", [
    (["--open-nodes", "50"], "--open-nodes must be in [120, 5000]"),
    (["--closed-nodes", "10"], "--closed-nodes must be in [24, 5000]"),
    (["--json", "/no/such/folder/k.json"], "output folder does not exist"),
])
def test_bad_input_exits_2_before_any_run(argv: list[str], match: str,
                                          capsys: pytest.CaptureFixture) -> None:
    assert main(["bench", "knots", *argv]) == 2
    assert match in capsys.readouterr().err
