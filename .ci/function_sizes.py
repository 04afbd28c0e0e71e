#!/usr/bin/env python3
"""Lengths of C++ function bodies, for .ci/check-sizes.

A small scanner, not a parser: it skips comments, string and character
literals (raw strings too) and preprocessor lines, and takes every brace
block whose opening statement holds a parameter list ')' -- and does not
start with a control keyword -- as a function (free functions, members
defined in a class body, constructors, top-level lambdas). The length runs
from the first line of the statement (the signature) to the closing brace;
lambdas and local classes count in the function that holds them.

Prints "<file>:<line>: <lines> <signature>" for each function longer than
the limit (argv[1]) among the files (argv[2:]).
"""
import re
import sys

CONTROL = re.compile(r'^(if|for|while|switch|catch|do|else|try|return|case|default)\b')


def functions(text):
    """Yields (start_line, end_line, signature) of outermost function bodies."""
    i, n, line = 0, len(text), 1
    statement, statement_line = [], None  # code since the last ; { }
    stack = []  # per open brace: (is_function, start_line, signature) or None
    in_function = 0
    at_line_start = True
    while i < n:
        c = text[i]
        if c == '\n':
            line += 1
            at_line_start = True
            i += 1
            if statement:
                statement.append(' ')
            continue
        if at_line_start and c == '#':  # preprocessor line (with continuations)
            while i < n and text[i] != '\n':
                if text[i] == '\\' and i + 1 < n and text[i + 1] == '\n':
                    line += 1
                    i += 1
                i += 1
            continue
        if not c.isspace():
            at_line_start = False
        if text.startswith('//', i):
            while i < n and text[i] != '\n':
                i += 1
            continue
        if text.startswith('/*', i):
            end = text.find('*/', i + 2)
            end = n if end < 0 else end + 2
            line += text.count('\n', i, end)
            i = end
            continue
        m = re.match(r'(?:u8|u|U|L)?R"([^()\\ ]{0,16})\(', text[i:i + 24])
        if m:
            close = ')' + m.group(1) + '"'
            end = text.find(close, i + m.end())
            end = n if end < 0 else end + len(close)
            line += text.count('\n', i, end)
            statement.append('""')
            i = end
            continue
        if c == '"' or (c == "'" and not (i > 0 and text[i - 1].isalnum())):
            j = i + 1
            while j < n and text[j] != c:
                j += 2 if text[j] == '\\' else 1
            line += text.count('\n', i, j)
            statement.append('""')
            i = j + 1
            continue
        if c == '{':
            sig = ''.join(statement).strip()
            is_function = (not in_function and ')' in sig and not CONTROL.match(sig)
                           and not sig.endswith('=') and not sig.startswith('namespace'))
            if is_function:
                in_function += 1
                stack.append((True, statement_line or line, ' '.join(sig.split())[:80]))
            else:
                if in_function:
                    in_function += 1
                stack.append(None)
            statement, statement_line = [], None
        elif c == '}':
            top = stack.pop() if stack else None
            if in_function:
                in_function -= 1
            if top:
                yield top[1], line, top[2]
            statement, statement_line = [], None
        elif c == ';':
            statement, statement_line = [], None
        else:
            if not statement and not c.isspace():
                statement_line = line
            if statement or not c.isspace():
                statement.append(c)
        i += 1


def main():
    limit = int(sys.argv[1])
    bad = 0
    for path in sys.argv[2:]:
        with open(path, encoding='utf-8', errors='replace') as f:
            text = f.read()
        for start, end, sig in functions(text):
            if end - start + 1 > limit:
                print(f'{path}:{start}: {end - start + 1} lines: {sig}')
                bad = 1
    return bad


if __name__ == '__main__':
    sys.exit(main())
