"""``python -m adhfit.cli``: the ``adhfit`` console script."""
import sys

from .main import main

sys.exit(main())
