"""MkDocs hook: the Sphinx cross-reference roles of the package's docstrings (``:func:`run```, ``:class:`~a.B```), which
mkdocstrings renders as plain text before the code span, are shown as the code span alone, the ``~`` (short name)
honoured. mkdocstrings has no option for reStructuredText roles in free-form docstrings, hence this hook."""
from __future__ import annotations

import re

ROLE = re.compile(r":(?:py:)?(?:func|class|mod|meth|attr|data|exc|obj|const|ref):(?=<code>)")
SHORT_NAME = re.compile(r"<code>~(?:[\w]+\.)*([\w]+)</code>")


def on_page_content(html: str, **kwargs) -> str:
    """Drop the role names in front of code spans and shorten ``~a.b.c`` to ``c``."""
    return SHORT_NAME.sub(r"<code>\1</code>", ROLE.sub("", html))
