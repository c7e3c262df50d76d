"""`kintsugi` on the command line (the console script, and `python -m kintsugi`).

The CLI is imported when it runs, not when this module is imported: a process that multiprocessing starts
(a campaign's worker, the sandbox's probe child) imports its parent's main script again, and the CLI's
libraries would cost each of them half a second.
"""


def main() -> None:
    from kintsugi.cli import app

    app()


if __name__ == "__main__":
    main()
