"""``python -m app.desktop [GRAMMAR] [--screenshot PATH] [--quit-after SECONDS]``."""
import sys

from app.desktop import main

if __name__ == "__main__":
    sys.exit(main())
