"""MkDocs hooks: the README's images (``renders/reference/``) are published with the site, so
the pages show them from where the repository keeps them (no second copy in ``docs/``); the
options page's table is made from the option schema at every build, and a benchmark's recorded
output is shown from its file, never pasted."""

import re
from pathlib import Path

from mkdocs.structure.files import File

ROOT = Path(__file__).resolve().parents[1]
#: Where the options page takes the schema's table.
OPTIONS_MARKER = "<!-- options-table -->"


#: ``<!-- recorded: FILE -->`` shows a recorded benchmark output (``benchmarks/record.py``).
RECORDED = re.compile(r"<!-- recorded: (\S+) -->")


def on_page_markdown(markdown, page, config, files):
    def recorded(found):
        text = (ROOT / found.group(1)).read_text().rstrip()
        return f"```text\n{text}\n```"

    markdown = RECORDED.sub(recorded, markdown)
    if OPTIONS_MARKER not in markdown:
        return markdown
    from tt_mujoco.sim import SCHEMA

    return markdown.replace(OPTIONS_MARKER, SCHEMA.markdown_table())


def on_files(files, config):
    for image in sorted((ROOT / "renders" / "reference").glob("*.png")):
        files.append(
            File(
                f"renders/reference/{image.name}",
                src_dir=str(ROOT),
                dest_dir=config["site_dir"],
                use_directory_urls=config["use_directory_urls"],
            )
        )
    return files
