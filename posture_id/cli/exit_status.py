"""The exit statuses of every command, one meaning each (issue 46; docs/development.md).

- :data:`ANSWERED` (0): the command did its work; an answer is written.
- :data:`DOUBTFUL` (1): an answer is written, but it should not be used as it stands:
  ``identify``'s verdict is doubtful or its model falls in re-simulation, ``fit`` did not
  converge (beyond the recording's noise), the simulated body left its sway limit, a
  recording of a cohort got no answer or a doubtful one, a study's trial got no FRF or a
  subject's fit is doubtful, ``compare`` found neither model within the recording's noise.
- :data:`REFUSED` (2): input refused before any work; one line names the file or flag
  and the problem.
- :data:`BUG` (3): an internal error; one line says so, ``--debug`` shows the traceback.
- :data:`INTERRUPTED` (130): Ctrl-C; finished work is kept.
"""

from __future__ import annotations

__all__ = ["ANSWERED", "DOUBTFUL", "REFUSED", "BUG", "INTERRUPTED", "EPILOG", "answered"]

ANSWERED = 0
DOUBTFUL = 1
REFUSED = 2
BUG = 3
INTERRUPTED = 130

#: The help text's last paragraph, for every command.
EPILOG = ("exit status: 0 answered; 1 answered and written, but doubtful (a doubtful "
          "verdict, a model that falls, a fit that did not converge, a body that fell, a "
          "cohort's recording or a study's trial without an answer, or with a doubtful one); "
          "2 input refused (one line says why); 3 a bug (--debug shows it); 130 interrupted "
          "(finished work kept)")


def answered(doubtful: bool) -> int:
    """:data:`DOUBTFUL` when the written answer is doubtful, :data:`ANSWERED` otherwise."""
    return DOUBTFUL if doubtful else ANSWERED
