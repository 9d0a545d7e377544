"""``python -m dnasim.cli``: the command line."""

import sys

from dnasim.cli.entry import main

sys.exit(main())
