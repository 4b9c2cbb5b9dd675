//! The user-facing contract ships with the repository: every help text that
//! cites "formats.md section N" or "method.md section N" points to docs/,
//! and the section exists there.

use std::process::Command;

fn help(args: &[&str]) -> String {
    let output = Command::new(env!("CARGO_BIN_EXE_posg-fsc"))
        .args(args)
        .arg("--help")
        .output()
        .unwrap();
    assert!(output.status.success());
    String::from_utf8(output.stdout).unwrap()
}

/// The subcommands listed by `posg-fsc --help`.
fn subcommands() -> Vec<String> {
    help(&[])
        .lines()
        .skip_while(|l| !l.starts_with("Commands:"))
        .skip(1)
        .take_while(|l| l.starts_with("  "))
        .filter_map(|l| l.split_whitespace().next().map(str::to_string))
        .filter(|c| c != "help")
        .collect()
}

/// The section numbers `## N.` of a document in docs/.
fn sections(document: &str) -> Vec<String> {
    let text = std::fs::read_to_string(format!("docs/{document}")).unwrap();
    text.lines()
        .filter_map(|l| l.strip_prefix("## "))
        .filter_map(|l| l.split_once('.').map(|(n, _)| n.to_string()))
        .collect()
}

#[test]
fn every_help_citation_points_to_an_existing_section_in_docs() {
    let commands = subcommands();
    assert!(commands.len() >= 15, "{commands:?}");
    let mut citations = 0;
    for command in std::iter::once(None).chain(commands.iter().map(Some)) {
        let text = help(
            command
                .map(|c| vec![c.as_str()])
                .unwrap_or_default()
                .as_slice(),
        );
        let text = text.split_whitespace().collect::<Vec<_>>().join(" ");
        for document in ["formats.md", "method.md"] {
            for (at, _) in text.match_indices(document) {
                citations += 1;
                assert!(
                    text[..at].ends_with("docs/"),
                    "`{command:?} --help` cites {document} outside docs/: {text}"
                );
                let number: String = text[at..]
                    .trim_start_matches(document)
                    .trim_start_matches(" section ")
                    .chars()
                    .take_while(char::is_ascii_digit)
                    .collect();
                assert!(
                    sections(document).contains(&number),
                    "`{command:?} --help` cites docs/{document} section {number}, which does not exist"
                );
            }
        }
    }
    assert!(citations >= 4, "{citations} citations found");
}

#[test]
fn the_documents_have_their_numbered_sections() {
    assert_eq!(
        sections("formats.md"),
        (1..=11).map(|n| n.to_string()).collect::<Vec<_>>()
    );
    assert_eq!(
        sections("method.md"),
        (1..=9).map(|n| n.to_string()).collect::<Vec<_>>()
    );
}

#[test]
fn the_guide_storm_recipe_is_the_script_the_cross_check_runs() {
    let guide = std::fs::read_to_string("docs/guide.md").unwrap();
    let recipe = std::fs::read_to_string("experiments/storm-check/recipe.py").unwrap();
    let block = guide
        .split("```python\n")
        .skip(1)
        .filter_map(|rest| rest.split("```").next())
        .find(|block| block.contains("def storm_value"))
        .expect("docs/guide.md has the Storm recipe as a python block");
    assert_eq!(
        block, recipe,
        "the Storm recipe of docs/guide.md differs from experiments/storm-check/recipe.py"
    );
    let run = std::fs::read_to_string("experiments/storm-check/run.py").unwrap();
    assert!(
        run.contains("from recipe import storm_value")
            && run.contains("storm_value(os.path.join(chain, \"chain.drn\")")
    );
}
