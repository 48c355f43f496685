#!/usr/bin/env python3
"""Fails when README.md quotes a figure docs/results.md does not hold.

    scripts/check-readme-figures.py README.md docs/results.md
    scripts/check-readme-figures.py --self-test

Checked: every number in README's generated block (between <!-- BEGIN results --> and
<!-- END results -->) and every percentage anywhere in README ("99.9 %", "0-0.1 %"). Each must be
a number of docs/results.md, written the same way. Exit 0 when all are, 1 naming each that is not,
2 on a usage or input error.
"""
import re
import sys

NUMBER = re.compile(r'(?<![\w.])\d+(?:\.\d+)?(?![\w.]*\w)')
PERCENT = re.compile(r'(\d+(?:\.\d+)?)(?:\s*-\s*(\d+(?:\.\d+)?))?\s?%')
BEGIN, END = '<!-- BEGIN results -->', '<!-- END results -->'


def numbers(text):
    return set(NUMBER.findall(text))


def quoted(readme):
    """(figure, where) pairs README quotes."""
    out = []
    i, j = readme.find(BEGIN), readme.find(END)
    if i < 0 or j < i:
        raise ValueError('README has no %s ... %s block' % (BEGIN, END))
    block = readme[i + len(BEGIN):j]
    for n in NUMBER.findall(block):
        out.append((n, 'the results block'))
    for line_no, line in enumerate(readme.splitlines(), 1):
        for m in PERCENT.finditer(line):
            for g in m.groups():
                if g is not None:
                    out.append((g, 'line %d' % line_no))
    return out


def check(readme, results):
    held = numbers(results)
    return ['%s (%s)' % (n, where) for n, where in quoted(readme) if n not in held]


def self_test():
    results = 'SucR 99.9 % [99.4, 100.0] of 1000; latency 0.033'
    good = 'x\n' + BEGIN + '\nSucR 99.9 % of 1000, 0.033 s\n' + END + '\nalso 99.4-100.0 %\n'
    assert check(good, results) == [], check(good, results)
    assert check(good.replace('0.033', '0.017'), results) == ['0.017 (the results block)']
    assert check(good + 'typed: 100 % success\n', results) == ['100 (line 6)'], check(good + 'typed: 100 % success\n', results)
    assert check(good.replace('99.9 %', '99.90 %'), results) != []  # written the same way
    try:
        check('no block', results)
        raise AssertionError('a README without the block was accepted')
    except ValueError:
        pass
    print('check-readme-figures: self-test passed')


def main(argv):
    if argv[1:] == ['--self-test']:
        self_test()
        return 0
    if len(argv) != 3:
        print(__doc__, file=sys.stderr)
        return 2
    try:
        readme = open(argv[1]).read()
        results = open(argv[2]).read()
        bad = check(readme, results)
    except (OSError, ValueError) as e:
        print('check-readme-figures: %s' % e, file=sys.stderr)
        return 2
    for b in bad:
        print('%s: quotes %s, which %s does not hold' % (argv[1], b, argv[2]))
    return 1 if bad else 0


if __name__ == '__main__':
    sys.exit(main(sys.argv))
