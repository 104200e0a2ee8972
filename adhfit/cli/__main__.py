"""``python -m adhfit.cli``: the ``adhfit`` console script."""
from .main import run

run()
