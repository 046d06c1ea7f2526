"""python -m kryflex: the kryflex command."""
import sys

from .cli import main

sys.exit(main())
