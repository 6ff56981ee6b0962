"""MkDocs hook: the README's images (``renders/reference/``) are published with the site, so
the pages show them from where the repository keeps them (no second copy in ``docs/``)."""

from pathlib import Path

from mkdocs.structure.files import File

ROOT = Path(__file__).resolve().parents[1]


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
