"""`make lint`'s size limits (scripts/check_sizes.py): a function over 60 lines or a module
over 400 fails, in Python and in C/C++, and the repository passes them."""

import subprocess
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
SCRIPT = REPO / "scripts" / "check_sizes.py"


def check(*roots) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, str(SCRIPT), *map(str, roots)], capture_output=True, text=True)


def test_long_functions_and_modules_fail_in_every_language(tmp_path):
    body = "\n".join(f"  x += {i};" for i in range(58))
    (tmp_path / "ok.cc").write_text(  # 60 lines: signature (2), body, brace
        "#include <x>\nnamespace a {\nstruct S {\n  int f() { return 1; }\n};\n"
        "int F(int x,\n      int y) {\n" + "\n".join(body.splitlines()[1:]) + "\n}\n}  // namespace a\n")
    (tmp_path / "long.cc").write_text("namespace a {\nTEST(A, B) {\n  // {\n" + body + "\n  x;\n  y;\n}\n}\n")
    (tmp_path / "long.py").write_text("def f():\n" + "    x = 1\n" * 60)
    (tmp_path / "big.h").write_text("int x;\n" * 401)
    out = check(tmp_path)
    assert out.returncode == 1
    lines = sorted(out.stdout.splitlines())
    assert lines == [f"{tmp_path.as_posix()}/big.h:1: module of 401 lines (limit 400)",
                     f"{tmp_path.as_posix()}/long.cc:2: function of 63 lines (limit 60): TEST(A, B)",
                     f"{tmp_path.as_posix()}/long.py:1: function f of 61 lines (limit 60)"], out.stdout


def test_the_repository_keeps_them():
    out = subprocess.run([sys.executable, str(SCRIPT)], capture_output=True, text=True, cwd=REPO)
    assert out.returncode == 0, out.stdout
