# Sphinx configuration for the two command pages of PE-JUMP
# (doc/fix_pe_jump.rst and doc/fix_pe_jump_async.rst) and its page of error
# details (doc/Errors_pe_jump.rst), in the manner of the LAMMPS manual's own
# doc/ build.  Build from the top of the repository with
#
#   sphinx-build -W --keep-going -c doc/sphinx -b html doc <output folder>
#
# or run tools/check_docs.sh, which does that and the other checks.
#
# The source folder is doc/ (so the pages keep their place and their relative
# :doc: links); this configuration and the index page live in doc/sphinx/.
#
# Two things of the LAMMPS manual are not here and are replaced:
#
# * The LAMMPS pages that the command pages link to with :doc: (fix nve,
#   run_style, ...).  They are listed, one page name a line, in
#   lammps_pages.txt beside this file; a :doc: link to a listed page becomes a
#   link to that page of the LAMMPS online manual (no stub pages, no
#   intersphinx).  A :doc: link to a page that is neither in the project nor in
#   the list stays a warning, i.e. an error under -W: add the page name to the
#   list only if the LAMMPS manual has it (tools/check_docs.sh checks the list
#   against the doc/src folder of a LAMMPS source tree when it finds one).
# * The LAMMPS pygments lexer for ``.. code-block:: LAMMPS``: a small lexer of
#   our own below (comments, the command word, numbers, variables, strings).

import glob
import os

from pygments.lexer import RegexLexer, bygroups
from pygments.token import Comment, Keyword, Name, Number, String, Text, Whitespace

HERE = os.path.dirname(os.path.abspath(__file__))

project = 'PE-JUMP'
author = 'The PE-JUMP developers'
copyright = 'the PE-JUMP developers'

root_doc = 'sphinx/index'
master_doc = root_doc
source_suffix = {'.rst': 'restructuredtext'}
exclude_patterns = ['_build', '**/_build']
extensions = ['sphinx.ext.mathjax']

# as in the LAMMPS manual: no highlighting of blocks that name no language,
# and the :lammps: role for inline input
highlight_language = 'none'
rst_prolog = r"""
.. role:: lammps(code)
   :language: LAMMPS
   :class: highlight
"""

html_theme = 'basic'
html_copy_source = False
html_show_sourcelink = False
# the pages link to the project's reports (doc/*.md) by relative links, which
# work where the repository is read; copy the reports beside the HTML pages so
# that the links work there too (as plain text)
html_extra_path = sorted(os.path.relpath(p, HERE)
                         for p in glob.glob(os.path.join(HERE, '..', '*.md')))

# -- links to the LAMMPS manual ---------------------------------------------

LAMMPS_MANUAL_URL = os.environ.get('LAMMPS_MANUAL_URL', 'https://docs.lammps.org/')


def read_lammps_pages():
    pages = set()
    with open(os.path.join(HERE, 'lammps_pages.txt')) as f:
        for line in f:
            line = line.split('#', 1)[0].strip()
            if line:
                pages.add(line)
    return pages


LAMMPS_PAGES = read_lammps_pages()


def resolve_lammps_page(app, env, node, contnode):
    """A :doc: link to a LAMMPS page listed in lammps_pages.txt -> the online manual."""
    if node.get('reftype') != 'doc':
        return None
    target = node.get('reftarget', '').lstrip('/')
    if target not in LAMMPS_PAGES:
        return None
    from docutils import nodes
    ref = nodes.reference('', '', internal=False,
                          refuri=LAMMPS_MANUAL_URL + target + '.html',
                          reftitle='LAMMPS manual: ' + target)
    ref += contnode
    return ref


# -- a LAMMPS lexer for code-block:: LAMMPS ---------------------------------

class LAMMPSLexer(RegexLexer):
    """Input lines of LAMMPS: a command word, then its arguments."""
    name = 'LAMMPS'
    aliases = ['lammps']
    tokens = {
        'root': [
            (r'\s*#.*?$', Comment.Single),
            (r'^(\s*)([a-z_][a-z0-9_/]*)', bygroups(Whitespace, Keyword)),
            (r'\$\{[^}]*\}|\$\([^)]*\)|\$[A-Za-z]', Name.Variable),
            (r'\b[vcf]_[A-Za-z0-9_]+(\[[0-9*]+\])?', Name.Variable),
            (r'"[^"]*"|\'[^\']*\'', String),
            (r'[-+]?(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?\b', Number),
            (r'&\s*$', Text),
            (r'[^\s#$"\']+', Text),
            (r'\s+', Whitespace),
        ],
    }


def setup(app):
    from sphinx.highlighting import lexers
    lexers['LAMMPS'] = LAMMPSLexer(startinline=True)
    app.connect('missing-reference', resolve_lammps_page)


# -- spelling (sphinx-build -b spelling, with sphinxcontrib.spelling) --------
# as in the LAMMPS manual: American English and a word list of the project

try:
    import importlib.util
    if importlib.util.find_spec('sphinxcontrib.spelling') and importlib.util.find_spec('enchant'):
        extensions.append('sphinxcontrib.spelling')
        spelling_lang = 'en_US'
        spelling_word_list_filename = [os.path.join(HERE, 'spelling_wordlist.txt')]
        spelling_warning = True
        spelling_show_suggestions = False
        spelling_ignore_pypi_package_names = False
        spelling_ignore_importable_modules = False
        spelling_ignore_contributor_names = False
except Exception:  # enchant present but no dictionary: no spelling builder
    pass
