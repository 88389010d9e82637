"""The README's Python quick start runs as printed and says what it claims."""

import contextlib
import io
import pathlib
import re

README = pathlib.Path(__file__).resolve().parents[3] / "README.md"


def test_the_python_quick_start_runs():
    text = README.read_text(encoding="utf-8")
    section = text[text.index("### Python"):]
    code = re.search(r"```python\n(.*?)```", section, re.S).group(1)
    printed = io.StringIO()
    with contextlib.redirect_stdout(printed):
        exec(compile(code, str(README), "exec"), {})
    lines = printed.getvalue().splitlines()
    assert lines[0].startswith("Roadmap(3-RPR: 7 regions, 24 patches")
    assert lines[1].startswith("Plan(connected, global path 64 -> 56 -> 24 -> 12")
    assert lines[2] == "[[64, 56, 24, 12], [64, 42, 24, 12]]"
    assert lines[3].endswith("True 0.0184")
