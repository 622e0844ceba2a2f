"""One probe of the shader budgets' measurement (benchmarks/shader_budgets.py): N lights of one kind, every light
forced to one ladder step, fog added by the operator, one tiny render (Cycles SVM, Cycles OSL, or EEVEE on the
saved and reopened file); prints ``PROBE_JSON {...}``.  The verdict (a shader too big, a crash, a black material)
is read from the process's log by ``shader_budgets.run_probe``.

    python tests/scenes/shader_budgets.py KIND STEP ENGINE N [--g G] [--passes] [--top]
"""
import pathlib
import sys

ROOT = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "benchmarks"))

import shader_budgets  # noqa: E402

if __name__ == "__main__":
    sys.argv = [sys.argv[0], "probe", *sys.argv[1:]]
    shader_budgets.main()
