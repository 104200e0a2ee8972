"""The README's test command and .ci/run must not drift apart (CI runs the README's command)."""
from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def _commands():
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    first = text.split("\n## ", 2)[1]  # the section right after the title
    return re.findall(r"```bash\n(.+?)\n```", first, flags=re.S)


def test_readme_opens_with_exactly_two_commands():
    cmds = _commands()
    assert len(cmds) == 2, cmds
    assert all("\n" not in c for c in cmds), "each command is one copy-paste line"


def test_ci_runs_the_readme_test_command_verbatim():
    test_cmd = _commands()[1]
    assert "pytest" in test_cmd
    ci = (ROOT / ".ci" / "run").read_text(encoding="utf-8")
    assert test_cmd in ci.splitlines()
