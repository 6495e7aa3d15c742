//! `drivemap import` through the binary, as a user runs it: a draft from a fixture manual that
//! `drivemap check --require-manuals` accepts as a draft (every citation verified by content),
//! the report, and `--merge` against a map with a register missing and a default changed.

use drivemap_test_support::paths;

use crate::common;

use std::path::PathBuf;
use std::process::Command;

use common::{command, repo};

fn drivemap() -> Command {
    let mut c = command();
    c.env("DRIVEMAP_MANUALS", paths::fixture("import/manuals"));
    c
}

fn tmp(name: &str) -> PathBuf {
    let dir =
        std::env::temp_dir().join(format!("drivemap-cli-import-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

#[test]
fn a_draft_checks_as_a_draft_with_every_citation_verified() {
    let dir = tmp("draft");
    let draft = dir.join("kestrel-k20.yaml");
    let report = dir.join("report.md");
    let manual = paths::fixture("import/manuals/kestrel-k20.txt");
    let out = drivemap()
        .args(["import", "--manual"])
        .arg(&manual)
        .args(["--id", "kestrel-k20", "-o"])
        .arg(&draft)
        .arg("--report")
        .arg(&report)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(stderr.contains("9 rows proposed"), "{stderr}");
    let yaml = std::fs::read_to_string(&draft).unwrap();
    assert!(
        yaml.contains("\ndraft:\n  by: \"drivemap import\""),
        "{yaml}"
    );
    let report = std::fs::read_to_string(&report).unwrap();
    assert!(report.contains("protocol.max_write: not found"), "{report}");

    let out = drivemap()
        .args(["check", "--require-manuals"])
        .arg(&draft)
        .output()
        .unwrap();
    let text = format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(out.status.success(), "{text}");
    assert!(
        text.contains("warning: a draft (made by drivemap import)"),
        "{text}"
    );
    assert!(text.contains("0 unverified"), "{text}");

    // `coverage` reads the draft's citations: every row of the manual's tables is covered.
    let out = drivemap().arg("coverage").arg(&draft).output().unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{text}{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(text.contains(" 0 uncited"), "{text}");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn merge_proposes_what_the_map_lacks_and_names_what_disagrees() {
    let dir = tmp("merge");
    let truth = std::fs::read_to_string(paths::fixture("import/orion-od5.yaml")).unwrap();
    // A map that lacks P2.04 and says 70.00 Hz where the manual prints a 60.00 default.
    let map: String = truth
        .lines()
        .filter(|l| !l.contains("param: P2.04"))
        .map(|l| l.replace("max: 400.0, default: 60.0", "max: 400.0, default: 70.0"))
        .collect::<Vec<_>>()
        .join("\n");
    let path = dir.join("orion-od5.yaml");
    std::fs::write(&path, map).unwrap();
    let out = drivemap()
        .args(["import", "--manual"])
        .arg(paths::fixture("import/manuals/orion-od5.txt"))
        .arg("--merge")
        .arg(&path)
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(text.contains("# 1 rows the map lacks"), "{text}");
    assert!(
        text.contains("param: \"P2.04\"") && text.contains("source: \"orion-od5.txt:40\""),
        "{text}"
    );
    assert!(
        text.contains("# 1 registers where the map and the manual's row disagree"),
        "{text}"
    );
    assert!(
        text.contains("maximum_frequency (orion-od5.txt:21)")
            && text.contains("default: map 70 / manual 60"),
        "{text}"
    );
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn columns_name_the_table_the_report_could_not_read() {
    let dir = tmp("columns");
    let manual = paths::fixture("import/manuals/vesper-vs2.txt");
    let report = dir.join("report.md");
    let out = drivemap()
        .args(["import", "--manual"])
        .arg(&manual)
        .args(["--id", "vesper-vs2", "--report"])
        .arg(&report)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = std::fs::read_to_string(&report).unwrap();
    assert!(
        text.contains("vesper-vs2.txt:5: column 3 \"Lo\" of this table is not understood")
            && text.contains("--columns 5:address,name,?,?,?,unit"),
        "{text}"
    );
    let yaml = String::from_utf8_lossy(&out.stdout);
    assert!(
        !yaml.contains("\n        min:") && !yaml.contains("\n        default:"),
        "{yaml}"
    );

    let out = drivemap()
        .args(["import", "--manual"])
        .arg(&manual)
        .args([
            "--id",
            "vesper-vs2",
            "--columns",
            "5:address,name,min,max,default,unit",
        ])
        .output()
        .unwrap();
    let yaml = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(
        yaml.contains("min: -10") && yaml.contains("default: 120") && yaml.contains("signed: true"),
        "{yaml}"
    );

    // A role the reader does not know is refused, naming the roles it knows.
    let out = drivemap()
        .args(["import", "--manual"])
        .arg(&manual)
        .args(["--id", "vesper-vs2", "--columns", "5:address,nom"])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && stderr.contains("`nom` is not a column role"),
        "{stderr}"
    );
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn merge_says_how_many_rows_it_read_before_anything_agrees() {
    let dir = tmp("merge-read");
    // A manual with no register table: nothing read, and the merge says so first.
    let manual = dir.join("prose.txt");
    std::fs::write(&manual, "A drive manual.\nIt speaks Modbus RTU.\n").unwrap();
    let out = drivemap()
        .args(["import", "--manual"])
        .arg(&manual)
        .arg("--merge")
        .arg(paths::fixture("import/orion-od5.yaml"))
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let read = text.find("prose.txt: 0 register rows read").expect(&text);
    let lacks = text.find("rows the map lacks").expect(&text);
    assert!(read < lacks, "{text}");
    assert!(text.contains("nothing below says the map agrees"), "{text}");
    std::fs::remove_dir_all(&dir).ok();
}

/// The registers of a draft as a reviewer compares them, without citations (a PDF's text is
/// laid out again, so its line numbers are not the text file's).
fn registers_of(yaml: &str, id: &str) -> Vec<String> {
    let drive = drivemap_map::Loader::new()
        .load_str(&format!("{id}.yaml"), yaml)
        .unwrap_or_else(|e| panic!("{e}\n{yaml}"));
    drive
        .registers()
        .map(|r| {
            let d = r.written();
            format!(
                "{} {:?} {} {:?} {:?} {:?} {:?} {:?} {:?} {} {:?} {:?}",
                d.address,
                d.param,
                d.name,
                d.unit,
                d.scale,
                d.min,
                d.max,
                d.default,
                d.access,
                d.signed,
                d.pair.map(|p| p.order),
                d.values
                    .iter()
                    .map(|v| (v.value, v.name.clone()))
                    .collect::<Vec<_>>()
            )
        })
        .collect()
}

#[test]
fn a_pdf_manual_imports_like_its_text() {
    // PDFs are written from the fixture manuals with fpdf2 and read back with poppler's
    // pdftotext, both installed by tests/interop/install.sh.
    let python = repo().join("target/interop-venv/bin/python");
    assert!(
        python.exists(),
        "{} missing: run tests/interop/install.sh",
        python.display()
    );
    const WRITE_PDF: &str = "import sys\nfrom fpdf import FPDF\npdf = FPDF(orientation='L', format='A4')\npdf.set_auto_page_break(True, margin=10)\npdf.add_page()\npdf.set_font('Courier', size=7)\nfor line in open(sys.argv[1], encoding='utf-8').read().split('\\n'):\n    pdf.cell(0, 3.5, line, new_x='LMARGIN', new_y='NEXT')\npdf.output(sys.argv[2])\n";
    let dir = tmp("pdf");
    for id in [
        "kestrel-k20",
        "orion-od5",
        "glacier-gx40",
        "ember-e8",
        "fjord-fx5",
        "lumen-l500",
        "borealis-bx3",
        "aurora-av15",
        "solstice-sx300",
        "halcyon-h8",
        "cirrus-c4",
        "vesper-vs2",
        "zephyr-z580",
        "tarn-t35",
        "meridian-m4",
    ] {
        let text = paths::fixture(format!("import/manuals/{id}.txt"));
        let pdf = dir.join(format!("{id}.pdf"));
        let out = Command::new(&python)
            .args(["-c", WRITE_PDF])
            .arg(&text)
            .arg(&pdf)
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let draft = dir.join(format!("{id}.yaml"));
        let out = drivemap()
            .args(["import", "--manual"])
            .arg(&pdf)
            .args(["--id", id, "-o"])
            .arg(&draft)
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(out.status.success(), "{id}: {stderr}");
        // The extracted text is kept beside the draft, and the draft cites it.
        let kept = dir.join(format!("{id}.txt"));
        assert!(
            kept.exists() && stderr.contains(&kept.display().to_string()),
            "{stderr}"
        );
        let from_pdf = std::fs::read_to_string(&draft).unwrap();
        assert!(
            from_pdf.contains(&format!("file: \"{id}.txt\"")),
            "{from_pdf}"
        );
        let out = drivemap()
            .args(["import", "--manual"])
            .arg(&text)
            .args(["--id", id])
            .output()
            .unwrap();
        let from_text = String::from_utf8_lossy(&out.stdout).into_owned();
        assert_eq!(
            registers_of(&from_pdf, id),
            registers_of(&from_text, id),
            "{id}: the PDF's draft differs from the text's"
        );
        assert!(!registers_of(&from_text, id).is_empty());
    }
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn a_pdf_without_pdftotext_is_a_clear_error() {
    let dir = tmp("nopdftotext");
    let pdf = dir.join("manual.pdf");
    std::fs::write(&pdf, b"%PDF-1.4\n").unwrap();
    let out = drivemap()
        .env("PATH", &dir)
        .args(["import", "--manual"])
        .arg(&pdf)
        .args(["--id", "x"])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && stderr.contains("pdftotext") && stderr.contains("poppler-utils"),
        "{stderr}"
    );
    std::fs::remove_dir_all(&dir).ok();
}
