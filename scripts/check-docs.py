#!/usr/bin/env python3
"""Checks that docs/ stays a reference a newcomer can follow.

    scripts/check-docs.py paths PAGE|DIR... every repository path and CHANGELOG section a page names exists
    scripts/check-docs.py words DOCS_DIR    the pages total at most --limit words (default 35000)
    scripts/check-docs.py --self-test       both checks fail on made-up pages

`paths` reads each backticked token that looks like a path of the repository (it has a '/', no space,
and starts with one of the repository's top-level folders or files) and fails, naming page and line,
when no such file or folder exists; tokens with placeholders (<name>, *, ...) and outputs (under build/
or out/, which a clean clone has not made yet) are skipped. It also fails on a pointer
`CHANGELOG.md, "Title"` whose title begins no heading of CHANGELOG.md. `words`
counts whitespace-separated words of DOCS_DIR/*.md without the generated parts: docs/results.md,
docs/performance.md and
the tables the code writes, between `<!-- BEGIN rotorguard keys` (or `bench --list`) and its `<!-- END ... -->`.
Exit 0 when the check holds, 1 naming what does not, 2 on a usage or input error.
"""
import glob
import os
import re
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
TICKED = re.compile(r'`([^`\s]+)`')
GENERATED_KEYS = re.compile(r'<!-- BEGIN rotorguard (keys|bench --list).*?<!-- END rotorguard (keys|bench --list)[^>]*-->', re.S)
GENERATED_PAGES = ('results.md', 'performance.md')  # written by scripts/results.py from its records
PLACEHOLDER = re.compile(r'[<>*]|\.\.\.')


def named_paths(text, root):
    """(line, path) of each backticked repository path in text."""
    tops = set(os.listdir(root)) - {'build', 'out'}
    out = []
    for line_no, line in enumerate(text.splitlines(), 1):
        for token in TICKED.findall(line):
            if '/' not in token or PLACEHOLDER.search(token) or '://' in token:
                continue
            if token.split('/', 1)[0] not in tops:
                continue
            out.append((line_no, token))
    return out


POINTER = re.compile(r'CHANGELOG\.md,\s+"([^"]+)"')


def changelog_headings(root):
    """CHANGELOG.md's headings, whitespace folded (none without the file)."""
    path = os.path.join(root, 'CHANGELOG.md')
    if not os.path.exists(path):
        return []
    with open(path) as f:
        return [' '.join(line.lstrip('#').split()) for line in f if line.startswith('#')]


def missing_paths(page, root, headings):
    """What `page` names that does not exist: repository paths, and CHANGELOG pointers whose title
    begins none of `headings`."""
    with open(page) as f:
        text = f.read()
    out = ['%s:%d: `%s` does not exist' % (page, line_no, p)
           for line_no, p in named_paths(text, root) if not os.path.exists(os.path.join(root, p))]
    for m in POINTER.finditer(text):
        title = ' '.join(m.group(1).split())
        if not any(h.startswith(title) for h in headings):
            out.append('%s:%d: CHANGELOG.md has no section "%s"' % (page, text.count('\n', 0, m.start()) + 1, title))
    return out


def pages_of(args):
    """The pages named: files as given, folders as their *.md."""
    out = []
    for a in args:
        out += sorted(glob.glob(os.path.join(a, '*.md'))) if os.path.isdir(a) else [a]
    return out


def reference_words(docs_dir):
    total = 0
    for page in sorted(glob.glob(os.path.join(docs_dir, '*.md'))):
        if os.path.basename(page) in GENERATED_PAGES:
            continue
        with open(page) as f:
            total += len(GENERATED_KEYS.sub('', f.read()).split())
    return total


def self_test():
    with tempfile.TemporaryDirectory() as root:
        os.makedirs(os.path.join(root, 'src', 'core'))
        open(os.path.join(root, 'src', 'core', 'a.cc'), 'w').close()
        page = os.path.join(root, 'page.md')
        with open(page, 'w') as f:
            f.write('Edit `src/core/a.cc`, then `src/core/b.cc`; not paths: `a/b`, `src/<name>.cc`.\n'
                    'History: CHANGELOG.md, "The first\nrelease"; CHANGELOG.md, "A lost section".\n')
        with open(os.path.join(root, 'CHANGELOG.md'), 'w') as f:
            f.write('# Changelog\n\n### The first release (formerly a page)\n')
        found = missing_paths(page, root, changelog_headings(root))
        assert len(found) == 2 and 'src/core/b.cc' in found[0] and 'A lost section' in found[1], found
        docs = os.path.join(root, 'docs')
        os.makedirs(docs)
        with open(os.path.join(docs, 'one.md'), 'w') as f:
            f.write('four words on this\n<!-- BEGIN rotorguard keys: x -->\nmany many many\n'
                    '<!-- END rotorguard keys -->\n')
        for generated in GENERATED_PAGES:
            with open(os.path.join(docs, generated), 'w') as f:
                f.write('generated words are not counted\n')
        assert reference_words(docs) == 4, reference_words(docs)
    print('check-docs: self-test passed')
    return 0


def main(argv):
    if argv[1:] == ['--self-test']:
        return self_test()
    limit = 35000
    args = argv[1:]
    if '--limit' in args:
        i = args.index('--limit')
        try:
            limit = int(args[i + 1])
        except (IndexError, ValueError):
            print('check-docs: --limit needs a whole number of words', file=sys.stderr)
            return 2
        del args[i:i + 2]
    if len(args) < 2 or args[0] not in ('paths', 'words'):
        print(__doc__, file=sys.stderr)
        return 2
    if args[0] == 'paths':
        problems = []
        headings = changelog_headings(ROOT)
        for page in pages_of(args[1:]):
            if not os.path.isfile(page):
                print('check-docs: %s: no such page' % page, file=sys.stderr)
                return 2
            problems += missing_paths(page, ROOT, headings)
        for p in problems:
            print(p)
        return 1 if problems else 0
    if not os.path.isdir(args[1]):
        print('check-docs: %s: no such folder' % args[1], file=sys.stderr)
        return 2
    n = reference_words(args[1])
    print('check-docs: %s holds %d words without its generated parts (at most %d)' % (args[1], n, limit))
    return 1 if n > limit else 0


if __name__ == '__main__':
    sys.exit(main(sys.argv))
