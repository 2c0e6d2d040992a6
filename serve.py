"""CBM Explorer: the live CBM calibration explorer in the browser (installed: the ``cbm-explorer`` command).

    python serve.py [--dataset PATH_OR_NAME] [--preset NAME] [--host 127.0.0.1] [--port 8080]
"""
import sys

from app.commands import serve as main

if __name__ == "__main__":
    sys.exit(main())
