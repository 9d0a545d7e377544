"""``python -m dnasim``: the command line (see ``dnasim.entry``)."""

import sys

from dnasim.entry import main

sys.exit(main())
