"""``python -m dnasim``: the command line (see ``dnasim.cli.entry``)."""

import sys

from dnasim.cli.entry import main

sys.exit(main())
