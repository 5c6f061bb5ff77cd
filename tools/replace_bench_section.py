"""Replace the text between <!-- bench:NAME:begin --> and <!-- bench:NAME:end -->
in a Markdown file (appending the markers if they are missing).

    python3 tools/replace_bench_section.py DOC NAME TABLE_TEXT
"""
import sys


def main() -> None:
    path, name, table = sys.argv[1], sys.argv[2], sys.argv[3]
    text = open(path).read()
    begin, end = f"<!-- bench:{name}:begin -->", f"<!-- bench:{name}:end -->"
    if begin in text and end in text:
        text = text[: text.index(begin) + len(begin)] + "\n" + table + "\n" + text[text.index(end):]
    else:
        text += "\n" + begin + "\n" + table + "\n" + end + "\n"
    open(path, "w").write(text)


if __name__ == "__main__":
    main()
