"""Foundations every layer uses: argument validation (``validation``), numbers in words
(``format``), HTML display in notebooks (``display``), atomic file writes (``atomic``) and the
MATLAB file reader (``matfile``)."""
