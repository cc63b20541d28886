#!/usr/bin/env bash
# Lists every function body longer than a limit (default 80 lines, from the
# line of its opening brace to the line of its closing one) in the project's
# own code (not tests/), longest first: "LINES file:first-last name". Issue 10
# asks for none; exits 1 when there is one. A text scan, not a parser: it
# follows braces past comments, strings and character literals, and takes a
# brace as a function body's when it opens at namespace or class level after a
# parameter list (lambdas and local classes count toward their function).
#   vcan-scripts/long-functions.sh [LIMIT] [ROOT]
set -euo pipefail
limit=${1:-80}
root=${2:-$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)}
cd "$root"

python3 - "$limit" slam control daemon drivers sim io robot types proto <<'EOF'
import os, re, sys

limit = int(sys.argv[1])
dirs = sys.argv[2:]


def strip(text):
    """The text with comments, string and character literals blanked (newlines kept)."""
    out, i, n = [], 0, len(text)
    while i < n:
        c = text[i]
        if text.startswith('//', i):
            j = text.find('\n', i)
            j = n if j < 0 else j
            i = j
        elif text.startswith('/*', i):
            j = text.find('*/', i + 2)
            j = n if j < 0 else j + 2
            out.append(re.sub(r'[^\n]', ' ', text[i:j]))
            i = j
        elif c == 'R' and text.startswith('R"', i) and not (i and (text[i-1].isalnum() or text[i-1] == '_')):
            m = re.match(r'R"([^(]*)\(', text[i:])
            end = text.find(')' + m.group(1) + '"', i) if m else -1
            j = n if end < 0 else end + len(m.group(1)) + 2
            out.append('""' + re.sub(r'[^\n]', ' ', text[i + 2:j]))
            i = j
        elif c in '"\'':
            if c == "'" and i and text[i-1].isalnum():  # digit separator 1'000
                out.append(' ')
                i += 1
                continue
            j = i + 1
            while j < n and text[j] != c:
                j += 2 if text[j] == '\\' else 1
            out.append(c + ' ' * (j - i - 1) + c)
            i = j + 1
        else:
            out.append(c)
            i += 1
    return ''.join(out)


def top_level_equals(header):
    depth = 0
    for k, c in enumerate(header):
        if c in '([<':
            depth += 1
        elif c in ')]>':
            depth -= 1
        elif c == '=' and depth <= 0:
            if header[k-1:k+1] in ('==', '!=', '<=', '>=') or header[k:k+2] == '==':
                continue
            if re.search(r'operator\s*\S*$', header[:k+1]):
                continue
            return True
    return False


def functions(path):
    text = strip(open(path, encoding='utf-8', errors='replace').read())
    # The open braces: (kind, line, name); kind 'scope' (namespace, class, enum),
    # 'body' (a function's), 'init' (a brace initialiser in a constructor's
    # member list) or 'inner' (anything else, inside a body or an initialiser).
    stack = []
    header_start = 0
    found = []
    line = 1
    for i, c in enumerate(text):
        if c == '\n':
            line += 1
        elif c in ';}{':
            if c == '{':
                header = text[header_start:i]
                in_body = any(k[0] == 'body' for k in stack)
                flat = ' '.join(header.split())
                if in_body:
                    kind = 'inner'
                elif stack and stack[-1][0] == 'init':
                    kind = 'init'
                elif re.match(r'^(.*\b)?(namespace|class|struct|union|enum)\b', flat) and '(' not in flat.split('{')[0].split(':')[0]:
                    kind = 'scope'
                elif flat.startswith('extern "'):
                    kind = 'scope'
                elif re.search(r'\)[\s\w]*:[^:].*[\w>]$', flat):
                    kind = 'init'  # a member's brace initialiser in a constructor's list
                elif ')' in flat and not top_level_equals(flat):
                    kind = 'body'
                else:
                    kind = 'inner'
                name = ''
                if kind == 'body':
                    m = re.search(r'([~\w:]+)\s*\(', flat)
                    name = m.group(1) if m else flat[:40]
                stack.append((kind, line, name))
                if kind == 'init':
                    continue  # the constructor's header goes on
            elif c == '}' and stack:
                kind, first, name = stack.pop()
                if kind == 'body':
                    found.append((line - first + 1, first, line, name))
                if kind == 'init':
                    continue  # the constructor's header goes on
            header_start = i + 1
        elif c == ':' and text[i-1:i+1] != '::' and text[i:i+2] != '::':
            # "public:" / "private:" labels end a header.
            if re.search(r'\b(public|private|protected)\s*$', text[header_start:i]):
                header_start = i + 1
    return found


rows = []
for d in dirs:
    for dirpath, _, files in os.walk(d):
        for f in sorted(files):
            if f.endswith(('.cc', '.h', '.cpp', '.hpp')):
                p = os.path.join(dirpath, f)
                for length, first, last, name in functions(p):
                    if length > limit:
                        rows.append((length, f'{p}:{first}-{last}', name))
rows.sort(key=lambda r: (-r[0], r[1]))
for length, where, name in rows:
    print(f'{length:4d} {where} {name}')
sys.exit(1 if rows else 0)
EOF
