"""Suite-wide settings.

The NMPC's NLP is compiled to C once per machine (``rhnc.control.nmpc_codegen``); with the many
problem sizes the tests build, a cold cache would add minutes of compiling to the suite.
The tests therefore use the interpreted functions (the same solutions) unless
``RHNC_NMPC_CODEGEN`` is set; ``tests/rhnc/test_nmpc_codegen.py`` tests the compiled path.
"""

import os

os.environ.setdefault("RHNC_NMPC_CODEGEN", "0")
