"""python -m kryflex: the kryflex command."""
import sys

from .cli.main import main

sys.exit(main())
